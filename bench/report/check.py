"""Internal-consistency checks of a benchmark run (bench/run --check; the bench_quick test). They assert
correctness, never a wall time: the reference diffed with itself is exact; the path tracer's
error falls as its sample count grows; every cache render has records and finite metrics; speed-ups and
equal-time ratios are positive and finite; every file the report links exists.
"""

import os
import re

from .analysis import is_finite_number

METRICS = ("rmse", "relmse", "psnr_hdr", "psnr_ldr", "ssim")


def _check_metrics(where, metrics, problems):
    for k in METRICS:
        v = (metrics or {}).get(k)
        if not is_finite_number(v):
            problems.append("%s: metric %s is %r, not a finite number" % (where, k, v))
    if metrics and metrics.get("nonfinite"):
        problems.append("%s: the image has %s NaN/Inf pixels" % (where, metrics["nonfinite"]))


def check_results(results, out_dir):
    """Returns a list of problems (empty when consistent)."""
    problems = []
    scenes = [s for s in results["scenes"] if not s.get("skipped")]
    if not scenes:
        problems.append("no scene was benchmarked")
    for s in scenes:
        name = s["name"]
        if s.get("error"):
            problems.append("%s: %s" % (name, s["error"]))
            continue
        self_diff = s["reference"]["self_diff"]
        if self_diff.get("rmse") != 0 or self_diff.get("relmse") != 0:
            problems.append("%s: the reference diffed with itself is not exact (rmse %r, relmse %r)"
                            % (name, self_diff.get("rmse"), self_diff.get("relmse")))
        curve = s["pt_curve"]
        noise = s["reference"].get("noise_relmse")
        if not (is_finite_number(noise) and noise >= 0):
            problems.append("%s: the reference's measured noise is %r, not a number >= 0" % (name, noise))
        elif curve and is_finite_number(curve[-1]["metrics"]["relmse"]) and not noise < curve[-1]["metrics"]["relmse"]:
            problems.append("%s: the reference's noise (relMSE %.4g) is not below the path tracer's at %d spp (%.4g); "
                            "the reference has too few samples" % (name, noise, curve[-1]["spp"],
                                                                   curve[-1]["metrics"]["relmse"]))
        if len(curve) < 3:
            problems.append("%s: the path tracer curve has %d points; need at least 3" % (name, len(curve)))
        for c in curve:
            _check_metrics("%s pt %s" % (name, c["label"]), c["metrics"], problems)
        for a, b in zip(curve, curve[1:]):
            for k in ("relmse", "rmse"):
                if is_finite_number(a["metrics"][k]) and is_finite_number(b["metrics"][k]) and \
                        not b["metrics"][k] < a["metrics"][k]:
                    problems.append("%s: the path tracer's %s does not fall from %d spp (%.5g) to %d spp (%.5g)"
                                    % (name, k, a["spp"], a["metrics"][k], b["spp"], b["metrics"][k]))
        if curve and curve[-1]["spp"] <= curve[0]["spp"]:
            problems.append("%s: the path tracer curve's sample counts do not grow" % name)
        if not s["cache"]:
            problems.append("%s: no cache render" % name)
        for c in s["cache"]:
            where = "%s cache %s" % (name, c["tag"])
            if "error" in c:
                problems.append("%s: render failed: %s" % (where, c["error"]))
                continue
            if not (isinstance(c.get("records"), int) and c["records"] > 0):
                problems.append("%s: records is %r; a cache render must create records" % (where, c.get("records")))
            if not (is_finite_number(c.get("seconds")) and c["seconds"] > 0):
                problems.append("%s: seconds is %r" % (where, c.get("seconds")))
            _check_metrics(where, c.get("metrics"), problems)
            eq = c.get("equal_quality")
            if not eq:
                problems.append("%s: no equal-quality estimate" % where)
            else:
                if not (is_finite_number(eq.get("speedup")) and eq["speedup"] > 0):
                    problems.append("%s: equal-quality speed-up is %r, not positive" % (where, eq.get("speedup")))
                if eq.get("method") not in ("interpolated", "extrapolated", "extrapolated (<1 spp)"):
                    problems.append("%s: unknown equal-quality method %r" % (where, eq.get("method")))
            et = c.get("equal_time") or {}
            if "pt" not in et:
                problems.append("%s: no equal-time path tracer render: %s" % (where, et.get("error", "?")))
            else:
                _check_metrics(where + " equal-time pt", et["pt"]["metrics"], problems)
                if not (is_finite_number(et.get("relmse_ratio")) and et["relmse_ratio"] > 0):
                    problems.append("%s: equal-time error ratio is %r, not positive" % (where, et.get("relmse_ratio")))
    problems.extend(_check_links(out_dir))
    return problems


def _check_links(out_dir):
    path = os.path.join(out_dir, "report.html")
    if not os.path.isfile(path):
        return ["%s was not written" % path]
    with open(path, encoding="utf-8") as f:
        text = f.read()
    problems = []
    links = re.findall(r'(?:src|href)="([^"#][^"]*)"', text)
    for link in links:
        if re.match(r"^[a-z]+:", link):
            problems.append("report.html links outside its folder: %s" % link)
        elif not os.path.isfile(os.path.join(out_dir, link)):
            problems.append("report.html links %s, which does not exist" % link)
    if not any(l.endswith(".png") for l in links):
        problems.append("report.html shows no image")
    if "<svg" not in text:
        problems.append("report.html has no plot")
    return problems

