#!/usr/bin/env python3
"""Sensor points on the Cornell box: the cache against the path tracer (docs/points.md, "Measured").

A 60 x 60 grid of upward sensors 3 cm apart at 1.4 m (x and z from -0.885 to 0.885) in
scenes/cornell-box/cornell-box.json, against a path-traced reference (--ref-samples per point). For each
setting: the records (sensor records + hit-stage records), the median seconds of --repeats runs (the
JSON's `seconds`, 2 threads), sensors per second, the mean relative error of the illuminance, its mean
signed error (bias), the share of sensors within 2 sigma (the estimate's and the reference's combined)
and the mean relative sigma. The settings are alternated between the two estimators.

    python3 bench/points_cornell.py --irrcache build/irrcache
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "scenes", "cornell-box", "cornell-box.json")
SETTINGS = [
    ["--integrator", "pt", "--samples", "256"],
    ["--integrator", "ic", "--accuracy", "0.1"],
    ["--integrator", "pt", "--samples", "1024"],
    ["--integrator", "ic"],
    ["--integrator", "ic", "--accuracy", "0.3"],
    ["--integrator", "ic", "--accuracy", "0.3", "--light-samples", "1024"],
]


def run(exe, points, extra, out):
    subprocess.run([exe, "points", SCENE, "--points", points, "--format", "json", "-o", out, "--threads", "2",
                    *extra], check=True, stdout=subprocess.DEVNULL)
    with open(out) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--irrcache", default=os.path.join(ROOT, "build", "irrcache"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--ref-samples", type=int, default=8192)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="points_cornell.")
    points, out = os.path.join(tmp, "grid.txt"), os.path.join(tmp, "out.json")
    with open(points, "w") as f:
        for j in range(60):
            for i in range(60):
                f.write("%.4f 1.4 %.4f 0 1 0\n" % (-0.885 + 0.03 * i, -0.885 + 0.03 * j))
    ref = run(a.irrcache, points, ["--integrator", "pt", "--samples", str(a.ref_samples)], out)["points"]
    R = [p["illuminance"] for p in ref]
    RS = [p["sigma"] for p in ref]
    print("reference: %d samples per sensor, mean relative sigma %.2f %%" %
          (a.ref_samples, 100 * statistics.fmean(s / r for s, r in zip(RS, R))))
    print("| estimator | records (sensors + hits) | seconds | sensors/s | mean error | bias | within 2σ | mean σ |")
    print("|---|---|---|---|---|---|---|---|")
    for s in SETTINGS:
        times = []
        for _ in range(a.repeats):
            d = run(a.irrcache, points, s, out)
            times.append(d["seconds"])
        V = [p["illuminance"] for p in d["points"]]
        S = [p["sigma"] for p in d["points"]]
        t = statistics.median(times)
        err = statistics.fmean(abs(v - r) / r for v, r in zip(V, R))
        bias = statistics.fmean((v - r) / r for v, r in zip(V, R))
        inside = sum(abs(v - r) < 2 * (sv * sv + sr * sr) ** 0.5 for v, r, sv, sr in zip(V, R, S, RS)) / len(R)
        sigma = statistics.fmean(sv / v for sv, v in zip(S, V))
        recs = "%d + %d" % (d["records"], d.get("hit_records", 0)) if "ic" in s else "—"
        print("| `%s` | %s | %.2f | %.0f | %.2f %% | %+.2f %% | %.1f %% | %.2f %% |" %
              (" ".join(s[1:]), recs, t, len(V) / t, 100 * err, 100 * bias, 100 * inside, 100 * sigma))
    return 0


if __name__ == "__main__":
    sys.exit(main())
