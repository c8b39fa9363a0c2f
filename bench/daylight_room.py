#!/usr/bin/env python3
"""daylight_room.py: the cache against the path tracer on a daylit room's work plane (BENCHMARKS.md).

    python3 bench/daylight_room.py --irrcache build/irrcache [--scenes overcast,clear] [--repeats 3]
                                   [--spacing 1] [--seeds 1] [--ref-samples N] [--also NAME=EXE]
                                   [--pt-samples 256,1024,...] [--ic-rays 800,1600,...] [--no-scaling]

For each scene (scenes/interiors/sky-room-overcast.json, sky-room-clear.json): a grid of upward sensors at
0.8 m over the room's 5 m x 4 m floor (`irrcache points --grid 0 0 0 5 2.7 4 --spacing S`; S = 1 m gives
20 sensors); a path-traced reference of those sensors (--ref-samples paths each); then the path tracer at
256 ... 65536 samples (--pt-samples) and the cache at 800 ... 25600 hemisphere rays per record (--ic-rays;
and a quarter as many direct-light samples), each run with seeds 1 ... --seeds, the estimators alternated. A setting's error is
the mean over its seeds of the sensors' mean relative error of the illuminance against the reference;
sensors whose reference is below 5 % of the median (inside the furniture) are left out and counted. Its
time is the median over seeds and repeats of ic_points_compute's seconds (the JSON's `seconds`: no scene
load). Prints a table, then the least time each estimator needs to reach --target (default 2 %) mean
error, read log-log between the two settings around it (and the first setting below it), and their ratio;
then, unless --no-scaling, the cache's time at that setting for about 100, 1,000 and 10,000 sensors.

--also NAME=EXE runs the cache settings with a second binary too (for example the build before a change),
alternated with the first, its rows marked NAME. Python 3 standard library only.
"""

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BOX = ["0", "0", "0", "5", "2.7", "4"]


def points(exe, scene, spacing, extra, out, seed=None):
    cmd = [exe, "points", scene, "--grid", *BOX, "--spacing", str(spacing), "--format", "json", "-o", out,
           "--threads", "2", *extra]
    if seed is not None:
        cmd += ["--seed", str(seed)]
    subprocess.run(cmd, check=True)
    with open(out) as f:
        d = json.load(f)
    records = "%d + %d" % (d["records"], d.get("hit_records", 0))  # the sensors' + the hit stage's
    return d["seconds"], [p["illuminance"] for p in d["points"]], [p["sigma"] for p in d["points"]], records


def mean_error(values, ref, keep):
    return statistics.fmean(abs(v - r) / r for v, r, k in zip(values, ref, keep) if k)


def time_to(rows, target):
    """Least time to the target error: log-log between the settings around it, rows (time, error) in
    increasing cost; None if no setting reaches it."""
    for k, (t, e) in enumerate(rows):
        if e <= target:
            if k == 0:
                return t
            t0, e0 = rows[k - 1]
            if e0 <= e or t0 <= 0.0:
                return t
            s = math.log(t / t0) / math.log(e / e0)
            return t0 * (target / e0) ** s
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--irrcache", default=os.path.join(ROOT, "build", "irrcache"))
    ap.add_argument("--scenes", default="overcast,clear")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--spacing", type=float, default=1.0)
    ap.add_argument("--ref-samples", type=int, default=1048576)
    ap.add_argument("--target", type=float, default=0.02)
    ap.add_argument("--also", action="append", default=[], metavar="NAME=EXE")
    ap.add_argument("--pt-samples", default="256,1024,4096,16384,65536")
    ap.add_argument("--ic-rays", default="800,1600,3200,6400,12800,25600")
    ap.add_argument("--no-scaling", action="store_true")
    a = ap.parse_args()
    others = [x.split("=", 1) for x in a.also]
    tmp = tempfile.mkdtemp(prefix="daylight_room.")
    out = os.path.join(tmp, "p.json")
    for name in a.scenes.split(","):
        scene = os.path.join(ROOT, "scenes", "interiors", "sky-room-%s.json" % name)
        _, ref, ref_sigma, _ = points(a.irrcache, scene, a.spacing, ["--integrator", "pt", "--samples",
                                                                     str(a.ref_samples)], out)
        median = statistics.median(ref)
        keep = [r > 0.05 * median for r in ref]
        rel_sigma = statistics.fmean(s / r for s, r, k in zip(ref_sigma, ref, keep) if k)
        print("\n%s: %d sensors (%d left out: reference below 5 %% of the median), reference %d paths each, "
              "mean relative sigma %.3f %%" % (name, len(ref), keep.count(False), a.ref_samples, 100 * rel_sigma))
        pt_settings = [["--integrator", "pt", "--samples", n] for n in a.pt_samples.split(",")]
        ic_settings = [["--integrator", "ic", "--rays", n, "--light-samples", str(max(16, int(n) // 4))]
                       for n in a.ic_rays.split(",")]
        runs = [("pt", a.irrcache, pt_settings), ("ic", a.irrcache, ic_settings)]
        runs += [("ic " + n, exe, ic_settings) for n, exe in others]
        rows = {label: [] for label, _, _ in runs}
        for k in range(max(len(pt_settings), len(ic_settings))):
            for label, exe, settings in runs:  # alternated
                if k >= len(settings):
                    continue
                times, errors, rec = [], [], 0
                for seed in range(1, a.seeds + 1):
                    for _ in range(a.repeats):
                        t, v, _, rec = points(exe, scene, a.spacing, settings[k], out, seed)
                        times.append(t)
                    errors.append(mean_error(v, ref, keep))
                rows[label].append((" ".join(settings[k]), statistics.median(times), statistics.fmean(errors), rec))
        print("| estimator | setting | records (sensors + hits) | seconds (median) | mean error (%d seeds) |" % a.seeds)
        print("|---|---|---|---|---|")
        for label, _, _ in runs:
            for s, t, e, rec in rows[label]:
                print("| %s | `%s` | %s | %.4f | %.2f %% |" % (label, s, rec if label != "pt" else "—", t, 100 * e))
        best = {label: time_to([(t, e) for _, t, e, _ in rows[label]], a.target) for label in rows}
        for label in rows:
            print("%s: least time to %.0f %%: %s" % (label, 100 * a.target,
                                                     "%.4f s" % best[label] if best[label] else "not reached"))
        for label in rows:
            if label != "pt" and best["pt"] and best[label]:
                print("ratio pt / %s at equal error: %.1f" % (label, best["pt"] / best[label]))
        if a.no_scaling:
            continue
        # the cache's first setting at or below the target, on finer grids
        first = next((s for s, _, e, _ in rows["ic"] if e <= a.target), None)
        if first:
            setting = first.split()
            for spacing in (0.4472, 0.1414, 0.04472):
                times = []
                for _ in range(a.repeats):
                    t, v, _, rec = points(a.irrcache, scene, spacing, setting, out)
                    times.append(t)
                t = statistics.median(times)
                print("ic (%s), %d sensors (spacing %g m): %.3f s, %s records, %.0f sensors/s" %
                      (first, len(v), spacing, t, rec, len(v) / t))
    return 0


if __name__ == "__main__":
    sys.exit(main())
