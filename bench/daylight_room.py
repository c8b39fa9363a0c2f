#!/usr/bin/env python3
"""daylight_room.py: the cache against the path tracer on a daylit room's work plane (BENCHMARKS.md).

    python3 bench/daylight_room.py --irrcache build/irrcache [--scenes overcast,clear] [--repeats 3]

For each scene (scenes/interiors/sky-room-overcast.json, sky-room-clear.json): a 1 m grid of upward sensors
at 0.8 m over the room's 5 m x 4 m floor (`irrcache points --grid 0 0 0 5 2.7 4 --spacing 1`, 20 sensors);
a path-traced reference of those sensors (--ref-samples paths each); then the path tracer at 256 ... 65536
samples and the cache at 800 ... 25600 hemisphere rays per record (and light samples likewise for the
sun), each timed as the median of --repeats runs of ic_points_compute (the JSON's `seconds`: no scene load),
the two estimators alternated. Prints, per setting, the mean relative error against the reference and the
time, then the least time each estimator needs to reach --target (default 2 %) mean error and their ratio,
and the cache's time at that setting for about 100, 1,000 and 10,000 sensors (finer grids of the same room).
Python 3 standard library only.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BOX = ["0", "0", "0", "5", "2.7", "4"]


def points(exe, scene, spacing, extra, out):
    cmd = [exe, "points", scene, "--grid", *BOX, "--spacing", str(spacing), "--format", "json", "-o", out,
           "--threads", "2", *extra]
    subprocess.run(cmd, check=True)
    with open(out) as f:
        d = json.load(f)
    records = "%d + %d" % (d["records"], d.get("hit_records", 0))  # the sensors' + the hit stage's
    return d["seconds"], [p["illuminance"] for p in d["points"]], [p["sigma"] for p in d["points"]], records


def mean_error(values, ref):
    return statistics.fmean(abs(v - r) / r for v, r in zip(values, ref))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--irrcache", default=os.path.join(ROOT, "build", "irrcache"))
    ap.add_argument("--scenes", default="overcast,clear")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--ref-samples", type=int, default=1048576)
    ap.add_argument("--target", type=float, default=0.02)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="daylight_room.")
    out = os.path.join(tmp, "p.json")
    for name in a.scenes.split(","):
        scene = os.path.join(ROOT, "scenes", "interiors", "sky-room-%s.json" % name)
        _, ref, ref_sigma, _ = points(a.irrcache, scene, 1.0, ["--integrator", "pt", "--samples",
                                                               str(a.ref_samples)], out)
        rel_sigma = statistics.fmean(s / r for s, r in zip(ref_sigma, ref))
        print("\n%s: %d sensors, reference %d paths each, mean relative sigma %.3f %%" %
              (name, len(ref), a.ref_samples, 100 * rel_sigma))
        pt_settings = [["--integrator", "pt", "--samples", str(n)] for n in (256, 1024, 4096, 16384, 65536)]
        ic_settings = [["--integrator", "ic", "--rays", str(n), "--light-samples", str(max(16, n // 4))]
                       for n in (800, 1600, 3200, 6400, 12800, 25600)]
        rows = []
        for k in range(max(len(pt_settings), len(ic_settings))):
            for settings in (pt_settings, ic_settings):  # alternated
                if k >= len(settings):
                    continue
                times, err, rec = [], None, 0
                for _ in range(a.repeats):
                    t, v, _, rec = points(a.irrcache, scene, 1.0, settings[k], out)
                    times.append(t)
                    err = mean_error(v, ref)
                rows.append((" ".join(settings[k]), statistics.median(times), err, rec))
        print("| setting | records (sensors + hits) | seconds (median of %d) | mean error |" % a.repeats)
        print("|---|---|---|---|")
        for s, t, e, rec in rows:
            print("| `%s` | %s | %.4f | %.2f %% |" % (s, rec if "ic" in s else "—", t, 100 * e))
        best = {}
        for s, t, e, _ in rows:
            kind = "ic" if "integrator ic" in s else "pt"
            if e <= a.target and (kind not in best or t < best[kind][1]):
                best[kind] = (s, t)
        for kind in ("pt", "ic"):
            print("%s: least time to %.0f %%: %s" % (kind, 100 * a.target,
                                                     "%.4f s (%s)" % (best[kind][1], best[kind][0])
                                                     if kind in best else "not reached"))
        if "pt" in best and "ic" in best:
            print("ratio pt / ic at equal error: %.1f" % (best["pt"][1] / best["ic"][1]))
        if "ic" in best:
            setting = best["ic"][0].split()
            for spacing in (0.4472, 0.1414, 0.04472):
                times = []
                for _ in range(a.repeats):
                    t, v, _, rec = points(a.irrcache, scene, spacing, setting, out)
                    times.append(t)
                t = statistics.median(times)
                print("ic, %d sensors (spacing %g m): %.3f s, %s records, %.0f sensors/s" %
                      (len(v), spacing, t, rec, len(v) / t))
    return 0


if __name__ == "__main__":
    sys.exit(main())
