"""The arithmetic of the benchmark: equal-quality speed-ups from the path tracer's error-versus-time curve
(DESIGN.md section 11), medians, and the marked section of BENCHMARKS.md that bench/run owns.

Equal quality. The path tracer is rendered at 1, 2, 4, ... samples per pixel; each point gives (seconds,
relMSE). To find the time the path tracer needs to reach a cache render's relMSE e:
  * "interpolated": e lies between two measured points; straight-line interpolation of log(seconds)
    against log(relMSE) between them (the curve is close to a line of slope -1 there);
  * "extrapolated": e is below the lowest measured error; MSE is proportional to 1/spp, so the path
    tracer needs spp* = spp_last * e_last / e samples, and its time grows by the per-sample render time of
    the last point: t = t_last + (spp* - spp_last) * render_seconds_per_spp;
  * "extrapolated (<1 spp)": e is above the 1-spp error; the same law below 1 spp, from the fixed cost
    (load + acceleration structure) plus a fraction of one sample's time.
The speed-up is that time divided by the cache render's time. Errors are against a path-traced reference
with finite samples, so measured errors carry its noise (about e_last * spp_last / spp_ref); errors near that
floor make the speed-up unreliable, and the result says so.
"""

import math
import os
import statistics

BEGIN_MARK = "<!-- bench:begin -->"
END_MARK = "<!-- bench:end -->"


def median(values):
    return statistics.median(values) if values else float("nan")


def is_finite_number(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def equal_quality_time(curve, error, spp_ref=None):
    """Time the path tracer needs to reach `error` (relMSE).

    curve: list of dicts with spp, seconds, relmse and render_seconds (the render phase only), in
    increasing spp. Returns a dict: seconds, spp (the estimated sample count), method ("interpolated",
    "extrapolated", "extrapolated (<1 spp)") and below_reference_floor (bool), or None when the curve has
    no usable points or error is not a positive finite number.
    """
    pts = [p for p in curve if is_finite_number(p.get("relmse")) and p["relmse"] > 0 and p["seconds"] > 0]
    if not pts or not is_finite_number(error) or error <= 0:
        return None
    pts.sort(key=lambda p: p["spp"])
    first, last = pts[0], pts[-1]
    floor = last["relmse"] * last["spp"] / spp_ref if spp_ref else 0.0
    result = {"below_reference_floor": bool(floor and error < 2.0 * floor)}

    def per_spp(p):
        render = p.get("render_seconds")
        return (render if is_finite_number(render) and render > 0 else p["seconds"]) / p["spp"]

    if error < min(p["relmse"] for p in pts):
        spp = last["spp"] * last["relmse"] / error
        result.update(seconds=last["seconds"] + (spp - last["spp"]) * per_spp(last), spp=spp,
                      method="extrapolated")
        return result
    if error > first["relmse"]:
        spp = first["spp"] * first["relmse"] / error
        fixed = max(0.0, first["seconds"] - first["spp"] * per_spp(first))
        result.update(seconds=fixed + spp * per_spp(first), spp=spp, method="extrapolated (<1 spp)")
        return result
    # Walk the measured segments; the curve may be non-monotonic near the reference's noise floor, so the
    # first segment (from low spp up) that brackets the error wins: the least time that reaches it.
    for a, b in zip(pts, pts[1:]):
        lo, hi = sorted((a["relmse"], b["relmse"]))
        if lo <= error <= hi:
            if a["relmse"] == b["relmse"]:
                f = 0.0
            else:
                f = (math.log(error) - math.log(a["relmse"])) / (math.log(b["relmse"]) - math.log(a["relmse"]))
            seconds = math.exp(math.log(a["seconds"]) + f * (math.log(b["seconds"]) - math.log(a["seconds"])))
            spp = math.exp(math.log(a["spp"]) + f * (math.log(b["spp"]) - math.log(a["spp"])))
            result.update(seconds=seconds, spp=spp, method="interpolated")
            return result
    # error equals a single point's (one-point curve)
    result.update(seconds=first["seconds"], spp=first["spp"], method="interpolated")
    return result


def replace_marked_section(text, body):
    """text with everything between the bench markers replaced by body; the markers are appended at the end
    when absent (after a "# Benchmarks" title if the file is empty). Text outside the markers is never
    changed."""
    block = BEGIN_MARK + "\n" + body.rstrip("\n") + "\n" + END_MARK
    begin = text.find(BEGIN_MARK)
    end = text.find(END_MARK, begin + len(BEGIN_MARK)) if begin >= 0 else -1
    if begin >= 0 and end >= 0:
        return text[:begin] + block + text[end + len(END_MARK):]
    if begin >= 0 or text.find(END_MARK) >= 0:
        raise ValueError("BENCHMARKS.md has one bench marker without the other; fix the markers by hand")
    prefix = text
    if prefix and not prefix.endswith("\n"):
        prefix += "\n"
    if prefix:
        prefix += "\n"
    else:
        prefix = "# Benchmarks\n\n"
    return prefix + block + "\n"


def update_marked_file(path, body):
    """Rewrites only the marked section of the file at path (creating the file if needed), atomically."""
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except FileNotFoundError:
        text = ""
    new_text = replace_marked_section(text, body)
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(new_text)
    os.replace(tmp, path)
