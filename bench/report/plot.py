"""Log-log line plots as standalone SVG text (no plotting library): one polyline with markers per series,
decade grid lines, axis labels and a legend. Every series path carries class "series" and a data-label,
which the report's self-check and the browser test count."""

import html
import math

PALETTE = ["#222222", "#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2"]


def _ticks(lo, hi):
    """Tick values for a log axis spanning [lo, hi]: decades, plus 2 and 5 when the span is short."""
    d0, d1 = math.floor(math.log10(lo)), math.ceil(math.log10(hi))
    mults = (1, 2, 5) if d1 - d0 <= 2 else (1,)
    ticks = [m * 10.0 ** d for d in range(d0, d1 + 1) for m in mults]
    return [t for t in ticks if lo * 0.999 <= t <= hi * 1.001]


def _fmt(v):
    if v == 0:
        return "0"
    if 1e-3 <= abs(v) < 1e4:
        return ("%.3f" % v).rstrip("0").rstrip(".")
    return "%.0e" % v


def loglog_svg(series, x_label, y_label, title, width=560, height=380):
    """series: list of dicts {label, points: [(x, y), ...], color (optional), dashed (optional),
    marker_only (optional)}; points with a non-positive or non-finite coordinate are dropped."""
    clean = []
    for i, s in enumerate(series):
        pts = [(x, y) for x, y in s["points"]
               if x is not None and y is not None and math.isfinite(x) and math.isfinite(y) and x > 0 and y > 0]
        if pts:
            clean.append(dict(s, points=sorted(pts), color=s.get("color") or PALETTE[i % len(PALETTE)]))
    esc = html.escape
    if not clean:
        return ('<svg xmlns="http://www.w3.org/2000/svg" class="plot" width="%d" height="%d"><text x="10" y="20">'
                '%s: no data</text></svg>' % (width, height, esc(title)))
    xs = [x for s in clean for x, _ in s["points"]]
    ys = [y for s in clean for _, y in s["points"]]
    xlo, xhi = min(xs) / 1.3, max(xs) * 1.3
    ylo, yhi = min(ys) / 1.3, max(ys) * 1.3
    left, right, top, bottom = 70, 170, 30, 50
    pw, ph = width - left - right, height - top - bottom

    def sx(x):
        return left + pw * (math.log(x) - math.log(xlo)) / (math.log(xhi) - math.log(xlo))

    def sy(y):
        return top + ph * (1 - (math.log(y) - math.log(ylo)) / (math.log(yhi) - math.log(ylo)))

    out = ['<svg xmlns="http://www.w3.org/2000/svg" class="plot" viewBox="0 0 %d %d" width="%d" height="%d" '
           'font-family="sans-serif" font-size="11">' % (width, height, width, height),
           '<title>%s</title>' % esc(title),
           '<rect x="%d" y="%d" width="%d" height="%d" fill="white" stroke="#888"/>' % (left, top, pw, ph),
           '<text x="%d" y="18" font-size="13" font-weight="bold">%s</text>' % (left, esc(title))]
    for t in _ticks(xlo, xhi):
        x = sx(t)
        out.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#ddd"/>' % (x, top, x, top + ph))
        out.append('<text x="%.1f" y="%d" text-anchor="middle">%s</text>' % (x, top + ph + 15, _fmt(t)))
    for t in _ticks(ylo, yhi):
        y = sy(t)
        out.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#ddd"/>' % (left, y, left + pw, y))
        out.append('<text x="%d" y="%.1f" text-anchor="end">%s</text>' % (left - 5, y + 4, _fmt(t)))
    out.append('<text x="%.1f" y="%d" text-anchor="middle">%s</text>' % (left + pw / 2, height - 10, esc(x_label)))
    out.append('<text transform="translate(16 %.1f) rotate(-90)" text-anchor="middle">%s</text>'
               % (top + ph / 2, esc(y_label)))
    for i, s in enumerate(clean):
        d = " ".join("%s%.1f %.1f" % ("M" if j == 0 else "L", sx(x), sy(y)) for j, (x, y) in enumerate(s["points"]))
        style = 'stroke="%s" stroke-width="%s" fill="none"' % (s["color"], "0" if s.get("marker_only") else "1.8")
        if s.get("dashed"):
            style += ' stroke-dasharray="5 3"'
        out.append('<path class="series" data-label="%s" d="%s" %s/>' % (esc(s["label"]), d, style))
        for x, y in s["points"]:
            out.append('<circle cx="%.1f" cy="%.1f" r="3" fill="%s"><title>%s: %s s, %s</title></circle>'
                       % (sx(x), sy(y), s["color"], esc(s["label"]), _fmt(x), _fmt(y)))
        ly = top + 10 + 16 * i
        lx = left + pw + 10
        out.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="%s" stroke-width="2"%s/>'
                   % (lx, ly, lx + 18, ly, s["color"], ' stroke-dasharray="5 3"' if s.get("dashed") else ""))
        out.append('<circle cx="%d" cy="%d" r="3" fill="%s"/>' % (lx + 9, ly, s["color"]))
        out.append('<text x="%d" y="%d">%s</text>' % (lx + 24, ly + 4, esc(s["label"])))
    out.append("</svg>")
    return "\n".join(out)
