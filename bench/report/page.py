"""The benchmark's outputs from its results: the Markdown tables (for BENCHMARKS.md and the terminal) and the
visual report, one self-contained HTML page (<out>/report.html) whose images and record lists are files
beside it, linked relatively; nothing is fetched from the network.

The page carries a self-check (report.js, run on load): every <img> decoded, every plot has drawn series,
hovering a record on each record overlay shows its tooltip, and no script or resource error happened. It
writes the verdict into <pre id="selftest" data-status="pass|fail">, which the browser test reads from
Chromium's DOM dump.
"""

import html
import json
import math
import os
import re

from . import plot

HERE = os.path.dirname(os.path.abspath(__file__))
esc = html.escape

# Fields of one record in the records JavaScript file, in order (a flat array, this many numbers each).
RECORD_FIELDS = ["px", "py", "radius_px", "x", "y", "z", "radius", "a", "visible"]


def write_records_js(records_json, out_path, key, width, height):
    """Converts the list irrcache --records-json writes ([{x, y, z, radius, a, px, py, radius_px, visible}],
    px/py in pixels of the image) into a script that registers it as window.IC_RECORDS[key] (a script, not
    JSON, because pages opened from file:// cannot fetch files). Returns out_path."""
    with open(records_json) as f:
        records = json.load(f)
    flat = []
    for r in records:
        radius_px = r.get("radius_px")
        if radius_px is None:  # a list without pixel radii: show the record as a small dot
            radius_px = 2.0
        flat.extend([round(float(r["px"]), 2), round(float(r["py"]), 2), round(float(radius_px), 2),
                     float("%.6g" % r.get("x", 0)), float("%.6g" % r.get("y", 0)), float("%.6g" % r.get("z", 0)),
                     float("%.6g" % r.get("radius", 0)), float("%.6g" % r.get("a", 0)),
                     1 if r.get("visible", True) else 0])
    payload = {"width": width, "height": height, "count": len(records), "fields": RECORD_FIELDS, "data": flat}
    with open(out_path, "w") as f:
        f.write("window.IC_RECORDS = window.IC_RECORDS || {};\nwindow.IC_RECORDS[%s] = %s;\n"
                % (json.dumps(key), json.dumps(payload, separators=(",", ":"))))
    return out_path


# ------------------------------------------------------------------------------------------------------
# number formatting


def _num(x, fmt="%.4g"):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    return fmt % x


def _psnr(x):
    return "∞" if x is not None and x >= 999 else _num(x, "%.2f")


def _eq_quality(c):
    eq = c.get("equal_quality")
    if not eq:
        return "–", "–"
    how = eq["method"] + (", below reference noise" if eq.get("below_reference_floor") else "")
    return "%s s (%s spp, %s)" % (_num(eq["seconds"], "%.3g"), _num(eq["spp"], "%.3g"), how), \
        _num(eq.get("speedup"), "%.2f×")


def _eq_corrected(c):
    eq = c.get("equal_quality_corrected")
    if not eq:
        return "–", "–"
    speed = _num(eq.get("speedup"), "%.2f×")
    if eq.get("lower_bound"):
        speed = "≥ " + speed
    return _num(eq.get("relmse")), speed


def _eq_time(c):
    et = c.get("equal_time") or {}
    if "pt" not in et:
        return "–", "–"
    return _num(et["pt"]["metrics"]["relmse"]), _num(et.get("relmse_ratio"), "%.2f×")


PT_COLUMNS = ["spp", "seconds", "rays/s", "relMSE", "RMSE", "PSNR HDR", "PSNR LDR", "SSIM"]
CACHE_COLUMNS = ["strategy", "accuracy", "seconds", "records", "passes", "rays", "relMSE", "PSNR HDR", "PSNR LDR",
                 "SSIM", "PT time to equal relMSE", "equal-quality speed-up", "relMSE, noise-corrected",
                 "speed-up, noise-corrected", "PT relMSE at equal time", "equal-time error ratio"]


def _pt_row(c):
    m = c["metrics"]
    return [str(c["spp"]), _num(c["seconds"], "%.3f"), _num(c["rays_per_second"], "%.3g"), _num(m["relmse"]),
            _num(m["rmse"]), _psnr(m["psnr_hdr"]), _psnr(m["psnr_ldr"]), _num(m["ssim"], "%.4f")]


def _cache_row(c):
    acc = "default" if c["accuracy"] is None else "%g" % c["accuracy"]
    if "error" in c:
        return [c["strategy"], acc, "FAILED: " + c["error"].splitlines()[0]] + [""] * (len(CACHE_COLUMNS) - 3)
    m = c["metrics"]
    eq_t, eq_s = _eq_quality(c)
    et_e, et_r = _eq_time(c)
    cr_e, cr_s = _eq_corrected(c)
    return [c["strategy"], acc, _num(c["seconds"], "%.3f"), str(c.get("records", "–")), str(c.get("passes", "–")),
            _num(c["rays"], "%.3g"), _num(m["relmse"]), _psnr(m["psnr_hdr"]), _psnr(m["psnr_ldr"]),
            _num(m["ssim"], "%.4f"), eq_t, eq_s, cr_e, cr_s, et_e, et_r]


def _md_table(columns, rows):
    out = ["| " + " | ".join(columns) + " |", "|" + "|".join("---" for _ in columns) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(out)


def _machine_line(results):
    m = results["machine"]
    irr = results["irrcache"]
    return "%s, %s cores (nproc)%s; %s%s" % (
        m["cpu"], m["nproc"], ", %s GiB" % m["memory_gib"] if m.get("memory_gib") else "", irr["version"],
        " (git %s)" % irr["git"] if irr.get("git") else "")


METHOD_NOTE = (
    "Times are wall seconds from `irrcache render --stats` (scene loading included){repeat}. Errors are against "
    "a path-traced reference with its own seed; relMSE = mean of (a−b)²/(b²+0.01), PSNR HDR on linear values, "
    "PSNR LDR and SSIM on the 8-bit sRGB images (`irrcache diff`). **Equal-quality speed-up**: the time the path "
    "tracer needs to reach the cache render's relMSE — *interpolated* on the log-log curve of its measured points, "
    "or *extrapolated* beyond them (the column says which; see below) — divided by the cache render's time. "
    "**Equal-time error ratio**: relMSE of the path tracer given the cache render's time (`--time`) divided by the "
    "cache render's relMSE (above 1: the cache is better). \"below reference noise\" marks errors under twice the "
    "reference's own noise, where the speed-up is unreliable. **Noise-corrected**: the reference has noise of its "
    "own, which adds to every measured error (render and reference are independent); a second reference with "
    "another seed measures it (half the relMSE between the two), and the corrected columns subtract it from the "
    "cache render's error and from the path tracer's curve before comparing. Beyond the measured curve the path "
    "tracer is extrapolated with MSE ∝ spp^-s, s fitted to its last three points and kept in [1, 2]; \"≥\" marks "
    "corrected errors below a quarter of the reference's noise, which are raised to that quarter (a lower bound). "
    "The path tracer samples every pixel evenly; the cache render's final pass samples adaptively (its default, as "
    "in Frolov et al. 2012 §3.2), and each scene notes what adaptive sampling alone gives the path tracer.")


def markdown_section(results):
    rep = results.get("repeat", 1)
    out = ["## Irradiance cache against the path tracer (`bench/run`)", "",
           "Command: `%s`  " % results["command"],
           "Date: %s; machine: %s." % (results["date"], _machine_line(results)), "",
           METHOD_NOTE.format(repeat=", median of %d runs" % rep if rep > 1 else ""), ""]
    if results.get("quick"):
        out += ["*Quick run (`--quick`): tiny images and a low-sample reference; a smoke test, not figures to quote.*", ""]
    for s in results["scenes"]:
        if s.get("skipped") or s.get("error"):
            out += ["### %s — %s" % (s["name"], "skipped" if s.get("skipped") else "FAILED"), "",
                    s.get("skipped") or s.get("error"), ""]
            continue
        ref = s["reference"]
        noise = ref.get("noise_relmse")
        out += ["### %s — %d×%d, reference %d spp%s" % (
                    s["name"], s["width"], s["height"], ref["spp"],
                    ", its own noise relMSE %.3g" % noise if noise is not None else ""), "",
                "Path tracer:", "", _md_table(PT_COLUMNS, [_pt_row(c) for c in s["pt_curve"]]), ""]
        pa = s.get("pt_adaptive")
        if pa and s["pt_curve"]:
            last = s["pt_curve"][-1]
            out += ["The path tracer with adaptive sampling (the cache render's default) at %s spp: relMSE %.4g in "
                    "%.3f s, against %.4g in %.3f s sampling evenly." % (
                        pa["spp"], pa["metrics"]["relmse"], pa["seconds"], last["metrics"]["relmse"],
                        last["seconds"]), ""]
        out += ["Irradiance cache:", "", _md_table(CACHE_COLUMNS, [_cache_row(c) for c in s["cache"]]), ""]
    return "\n".join(out).rstrip("\n") + "\n"


# ------------------------------------------------------------------------------------------------------
# the HTML page


def _inline_markdown(text):
    """The little Markdown the notes use (`code`, **bold**, *italic*) as HTML."""
    text = esc(text, quote=False)
    text = re.sub(r"`([^`]+)`", r"<code>\1</code>", text)
    text = re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", text)
    return re.sub(r"\*([^*]+)\*", r"<i>\1</i>", text)


def _html_table(columns, rows):
    head = "".join("<th>%s</th>" % esc(c) for c in columns)
    body = "".join("<tr>%s</tr>" % "".join("<td>%s</td>" % esc(v) for v in r) for r in rows)
    return '<table class="figures"><thead><tr>%s</tr></thead><tbody>%s</tbody></table>' % (head, body)


def _display_width(w):
    """Small images are shown enlarged by a whole factor (pixelated); large ones at most 480 px wide."""
    if w < 240:
        return w * -(-240 // w)
    return min(w, 480)


def _figure(src, caption, w, h, cls=""):
    dw = _display_width(w)
    dh = int(round(h * dw / w))
    return ('<figure class="%s"><img src="%s" width="%d" height="%d" alt="%s"><figcaption>%s</figcaption></figure>'
            % (cls, esc(src), dw, dh, esc(re.sub(r"<[^>]+>", " ", caption)), caption))


def _caption(title, entry):
    m = entry["metrics"]
    return "<b>%s</b><br>%s s · relMSE %s · PSNR %s dB · SSIM %s" % (
        esc(title), _num(entry["seconds"], "%.3g"), _num(m["relmse"]), _psnr(m["psnr_ldr"]), _num(m["ssim"], "%.3f"))


def _plots(s):
    pt = [(c["seconds"], c["metrics"]["relmse"]) for c in s["pt_curve"]]
    pt_ssim = [(c["seconds"], 1 - c["metrics"]["ssim"]) for c in s["pt_curve"]]
    series_e = [{"label": "path tracer", "points": pt, "color": plot.PALETTE[0]}]
    series_s = [{"label": "path tracer", "points": pt_ssim, "color": plot.PALETTE[0]}]
    strategies = []
    for c in s["cache"]:
        if c["strategy"] not in strategies:
            strategies.append(c["strategy"])
    for i, st in enumerate(strategies):
        runs = [c for c in s["cache"] if c["strategy"] == st and "error" not in c]
        color = plot.PALETTE[1 + i % (len(plot.PALETTE) - 1)]
        series_e.append({"label": "cache, " + st, "color": color,
                         "points": [(c["seconds"], c["metrics"]["relmse"]) for c in runs]})
        series_s.append({"label": "cache, " + st, "color": color,
                         "points": [(c["seconds"], 1 - c["metrics"]["ssim"]) for c in runs]})
        et = [c["equal_time"]["pt"] for c in runs if c.get("equal_time", {}).get("pt")]
        series_e.append({"label": "pt at %s's times" % st, "color": color, "dashed": True,
                         "points": [(p["seconds"], p["metrics"]["relmse"]) for p in et]})
    return (plot.loglog_svg(series_e, "seconds", "relMSE", "%s: relMSE against time" % s["name"]),
            plot.loglog_svg(series_s, "seconds", "1 − SSIM", "%s: 1 − SSIM against time" % s["name"]))


def _records_overlay(s, c, has_records_json):
    w, h = s["width"], s["height"]
    dw = _display_width(w)
    dh = int(round(h * dw / w))
    key = "%s/%s" % (s["name"], c["tag"])
    if c.get("records_js"):
        note = ('Move the pointer over a record: its position, radius and a. <label><input type="checkbox" '
                'class="show-all"> show every influence circle</label>')
    elif has_records_json:
        note = "The render wrote no record list."
    else:
        note = ("This irrcache build has no <code>--records-json</code>, so the overlay is the image only; with it, "
                "hovering shows each record's position, radius and a.")
    return ('<div class="overlay-block"><h4>%s: %s records</h4><div class="overlay" data-key="%s" '
            'style="width:%dpx;height:%dpx"><img src="%s" width="%d" height="%d" alt="records of %s">'
            '<canvas width="%d" height="%d"></canvas><div class="tip" hidden></div></div><p class="note">%s</p></div>'
            % (esc(c["label"]), esc(str(c.get("records", "?"))), esc(key), dw, dh, esc(c["records_png"]), dw, dh,
               esc(c["label"]), dw, dh, note))


def _scene_section(s, results):
    name = s["name"]
    if s.get("skipped") or s.get("error"):
        return '<section id="%s"><h2>%s — %s</h2><p class="note">%s</p></section>' % (
            esc(name), esc(name), "skipped" if s.get("skipped") else "FAILED", esc(s.get("skipped") or s.get("error")))
    w, h = s["width"], s["height"]
    ref = s["reference"]
    parts = ['<section id="%s"><h2>%s — %d×%d, reference %d spp%s</h2>' % (
        esc(name), esc(name), w, h, ref["spp"], " (from the cache)" if ref.get("cached") else "")]
    parts.append("<h3>Figures</h3>")
    parts.append(_html_table(CACHE_COLUMNS, [_cache_row(c) for c in s["cache"]]))
    parts.append("<details><summary>Path tracer curve</summary>%s</details>"
                 % _html_table(PT_COLUMNS, [_pt_row(c) for c in s["pt_curve"]]))
    e_svg, s_svg = _plots(s)
    parts.append('<h3>Error against time</h3><div class="plots">%s%s</div>' % (e_svg, s_svg))

    parts.append("<h3>Side by side</h3><p class=\"note\">Each cache render with default settings, the path tracer "
                 "given the same time, their error heat maps (relative luma error; full red = %g) and, where "
                 "the build has them, their blotch maps (the error left after a blur of 2 pixels: red brighter "
                 "than the reference, blue darker; full at 0.05).</p>"
                 % results.get("heatmap_max", 0))
    parts.append('<div class="row">%s</div>' % _figure(ref["png"], "<b>reference</b><br>%d spp" % ref["spp"], w, h))
    for c in s["cache"]:
        if not c.get("default") or "error" in c:
            continue
        row = [_figure(c["png"], _caption("cache, " + c["label"], c), w, h)]
        pt = c.get("equal_time", {}).get("pt")
        if pt:
            row.append(_figure(pt["png"], _caption("path tracer, equal time (%s spp)" % pt["spp"], pt), w, h))
        row.append(_figure(c["heatmap"], "<b>heat map</b>, cache", w, h, "heat"))
        if pt:
            row.append(_figure(pt["heatmap"], "<b>heat map</b>, path tracer", w, h, "heat"))
        if c.get("blotch"):
            row.append(_figure(c["blotch"], "<b>blotches</b>, cache", w, h, "heat"))
        if pt and pt.get("blotch"):
            row.append(_figure(pt["blotch"], "<b>blotches</b>, path tracer", w, h, "heat"))
        parts.append('<div class="row">%s</div>' % "".join(row))

    if s.get("crops"):
        parts.append("<h3>Zoomed crops</h3>")
        for row in s["crops"]:
            rect = row["rect"]
            cw = max(1, int(round((rect[2] - rect[0]) * w)))
            ch = max(1, int(round((rect[3] - rect[1]) * h)))
            scale = 120 / ch  # every crop shown 120 px high, pixelated
            figs = "".join(
                '<figure class="crop"><img src="%s" width="%d" height="%d" alt="%s"><figcaption>%s</figcaption></figure>'
                % (esc(im["png"]), int(cw * scale), int(ch * scale), esc(im["label"]), esc(im["label"]))
                for im in row["images"])
            parts.append('<h4>%s <span class="note">(x %.2f–%.2f, y %.2f–%.2f of the image)</span></h4><div class="row">%s</div>'
                         % (esc(row["name"]), rect[0], rect[2], rect[1], rect[3], figs))

    overlays = [c for c in s["cache"] if c.get("default") and c.get("records_png")]
    if overlays:
        parts.append("<h3>Records</h3>")
        parts.append('<div class="row">%s</div>' % "".join(
            _records_overlay(s, c, results.get("has_records_json")) for c in overlays))

    gallery = []
    for c in s["cache"]:
        if "error" in c:
            continue
        gallery.append(_figure(c["png"], _caption("cache, " + c["label"], c), w, h, "small"))
        gallery.append(_figure(c["heatmap"], "heat map", w, h, "small heat"))
    for c in s["pt_curve"]:
        gallery.append(_figure(c["png"], _caption("path tracer, %d spp" % c["spp"], c), w, h, "small"))
    parts.append('<details><summary>Every render</summary><div class="row">%s</div></details>' % "".join(gallery))
    parts.append("</section>")
    return "\n".join(parts)


def _read(name):
    with open(os.path.join(HERE, name), encoding="utf-8") as f:
        return f.read()


def write_report(results, out_dir):
    scenes = results["scenes"]
    scripts = []
    for s in scenes:
        for c in s.get("cache", []):
            if c.get("records_js"):
                scripts.append('<script src="%s"></script>' % esc(c["records_js"]))
    nav = " · ".join('<a href="#%s">%s</a>' % (esc(s["name"]), esc(s["name"])) for s in scenes)
    rep = results.get("repeat", 1)
    method = _inline_markdown(METHOD_NOTE.format(repeat=", median of %d runs" % rep if rep > 1 else ""))
    doc = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>irrcache benchmark report</title>
<script>{early_js}</script>
<style>{css}</style>
{scripts}
</head><body>
<header><h1>irrcache: irradiance cache against the path tracer</h1>
<p>{quick}Command <code>{command}</code> · {date} · {machine}</p>
<p class="note">{method}</p>
<nav>{nav}</nav></header>
{sections}
<footer><h3>Page self-check</h3><pre id="selftest" data-status="pending">pending (needs JavaScript)</pre></footer>
<script>{js}</script>
</body></html>
""".format(early_js=_read("early.js"), css=_read("report.css"), scripts="\n".join(scripts),
           quick="<b>Quick run</b> (smoke test, not figures to quote) · " if results.get("quick") else "",
           command=esc(results["command"]), date=esc(results["date"]), machine=esc(_machine_line(results)),
           method=method, nav=nav, sections="\n".join(_scene_section(s, results) for s in scenes),
           js=_read("report.js"))
    path = os.path.join(out_dir, "report.html")
    with open(path + ".tmp", "w", encoding="utf-8") as f:
        f.write(doc)
    os.replace(path + ".tmp", path)
    return path
