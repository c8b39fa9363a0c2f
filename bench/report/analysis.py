"""The arithmetic of the benchmark: equal-quality speed-ups from the path tracer's error-versus-time curve
(bench/README.md), medians, and the marked section of BENCHMARKS.md that bench/run owns.

Equal quality. The path tracer is rendered at 1, 2, 4, ... samples per pixel; each point gives (seconds,
relMSE). To find the time the path tracer needs to reach a cache render's relMSE e:
  * "interpolated": e lies between two measured points; straight-line interpolation of log(seconds)
    against log(relMSE) between them (the curve is close to a line of slope -1 there);
  * "extrapolated": e is below the lowest measured error; MSE is proportional to spp^-s, s fitted to the
    last three points and kept in [1, 2] (1 = plain Monte Carlo; low-discrepancy sampling can do better), so
    the path tracer needs spp* = spp_last * (e_last / e)^(1/s) samples, and its time grows by the per-sample
    render time of the last point: t = t_last + (spp* - spp_last) * render_seconds_per_spp;
  * "extrapolated (<1 spp)": e is above the 1-spp error; the same law below 1 spp, from the fixed cost
    (load + acceleration structure) plus a fraction of one sample's time.
The speed-up is that time divided by the cache render's time. Errors are against a path-traced reference
with finite samples, so measured errors carry its noise. bench/run measures that noise with a second
reference of another seed (half the relMSE between the two) and also gives noise-corrected speed-ups, with
the noise subtracted from every error (see equal_quality_time); errors near the noise are unreliable either
way, and the result says so.
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


def _fitted_slope(pts):
    """Convergence order s of MSE ∝ spp^-s from the last three points (least squares in log-log), kept in
    [1, 2]: never slower than Monte Carlo's 1/spp, which would favour the cache."""
    tail = pts[-3:]
    if len(tail) < 2:
        return 1.0
    xs = [math.log(p["spp"]) for p in tail]
    ys = [math.log(p["relmse"]) for p in tail]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    if sxx <= 0:
        return 1.0
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
    return min(2.0, max(1.0, -slope))


def equal_quality_time(curve, error, spp_ref=None, ref_noise=None):
    """Time the path tracer needs to reach `error` (relMSE).

    curve: list of dicts with spp, seconds, relmse and render_seconds (the render phase only), in
    increasing spp. Returns a dict: seconds, spp (the estimated sample count), method ("interpolated",
    "extrapolated", "extrapolated (<1 spp)"), below_reference_floor (bool) and lower_bound (bool), or None
    when the curve has no usable points or error is not a positive finite number.

    ref_noise: the reference's own noise (its relMSE against the truth, measured from a second reference
    with another seed). Every measured error is the render's error plus that noise (the render and the
    reference are independent), so with ref_noise given, it is subtracted from the curve and from `error`
    before comparing: the noise-corrected estimate. An error that falls below a quarter of the noise
    after the subtraction cannot be resolved; it is raised to that quarter and the result marked
    lower_bound (the speed-up is at least the figure given).
    """
    pts = [p for p in curve if is_finite_number(p.get("relmse")) and p["relmse"] > 0 and p["seconds"] > 0]
    if not pts or not is_finite_number(error) or error <= 0:
        return None
    pts.sort(key=lambda p: p["spp"])
    result = {"below_reference_floor": False, "lower_bound": False}
    if is_finite_number(ref_noise) and ref_noise > 0:
        result["below_reference_floor"] = error < 2.0 * ref_noise
        resolvable = 0.25 * ref_noise
        pts = [dict(p, relmse=p["relmse"] - ref_noise) for p in pts if p["relmse"] - ref_noise > resolvable]
        if not pts:
            return None
        error -= ref_noise
        if error < resolvable:
            error, result["lower_bound"] = resolvable, True
    else:
        last = pts[-1]
        floor = last["relmse"] * last["spp"] / spp_ref if spp_ref else 0.0
        result["below_reference_floor"] = bool(floor and error < 2.0 * floor)
    first, last = pts[0], pts[-1]

    def per_spp(p):
        render = p.get("render_seconds")
        return (render if is_finite_number(render) and render > 0 else p["seconds"]) / p["spp"]

    if error < min(p["relmse"] for p in pts):
        order = _fitted_slope(pts)
        spp = last["spp"] * (last["relmse"] / error) ** (1.0 / order)
        result.update(seconds=last["seconds"] + (spp - last["spp"]) * per_spp(last), spp=spp,
                      method="extrapolated", order=order)
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
