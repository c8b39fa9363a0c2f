#!/usr/bin/env python3
"""hit_stage_oracle.py: what the sensors' hit stage costs, and what perfect hit records would give.

Needs a build with the measurement patch (it reads environment variables and prints from inside the
library, so it never ships):

    git apply bench/hit_stage_oracle.patch
    cmake -S . -B build-oracle -DCMAKE_BUILD_TYPE=Release && cmake --build build-oracle -j2 --target irrcache_cli
    git apply -R bench/hit_stage_oracle.patch
    python3 bench/hit_stage_oracle.py --irrcache build-oracle/irrcache [--scene overcast|clear]
        [--seeds 8] [--rays 400,800,1600] [--ref-samples 1048576]

The patched build reads ORC_DIV (the hit records' strata are the sensor records' over this, each way;
8 as shipped), ORC_PASSES (the hit stage's most passes; 12) and ORC_UNC (the share of uncovered probe
hits under which the passes stop), and with ORC_TIME prints the hit stage's seconds. The script runs the
sky-room's 20 sensors (`irrcache points SCENE --grid 0 0 0 5 2.7 4 --spacing 1`) as shipped and with
"perfect" hit records (ORC_DIV=1: as many rays as a sensor record; ORC_PASSES=40, ORC_UNC=0: passes
until no probe is uncovered), seeds 1 ... --seeds, and prints for each the mean relative error of the
illuminance against a path-traced reference (--ref-samples paths a sensor, computed once and kept in
--ref-file), each seed's mean signed error, and the median of the whole computation's seconds and of
the hit stage's (2 threads). Python 3 standard library only.
"""

import argparse
import json
import os
import statistics
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GRID = ["--grid", "0", "0", "0", "5", "2.7", "4", "--spacing", "1", "--threads", "2", "--format", "json"]
CONFIGS = {"as shipped": {}, "perfect hit records": {"ORC_DIV": "1", "ORC_PASSES": "40", "ORC_UNC": "0"}}


def run(exe, scene, extra, env):
    out = "hit_stage_oracle.json"
    pr = subprocess.run([exe, "points", scene, *GRID, "-o", out, *extra], check=True, env=env,
                        stderr=subprocess.PIPE, text=True)
    hit = [float(l.split()[3]) for l in pr.stderr.splitlines() if l.startswith("ORC hit stage")]
    with open(out) as f:
        d = json.load(f)
    os.remove(out)
    return d, (hit[0] if hit else float("nan"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--irrcache", required=True)
    ap.add_argument("--scene", default="overcast", choices=["overcast", "clear"])
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--rays", default="400,800,1600")
    ap.add_argument("--ref-samples", type=int, default=1048576)
    ap.add_argument("--ref-file", default=None)
    a = ap.parse_args()
    scene = os.path.join(ROOT, "scenes", "interiors", "sky-room-%s.json" % a.scene)
    ref_file = a.ref_file or "sky-room-%s-ref%d.json" % (a.scene, a.ref_samples)
    if not os.path.exists(ref_file):
        d, _ = run(a.irrcache, scene, ["--integrator", "pt", "--samples", str(a.ref_samples)], dict(os.environ))
        with open(ref_file, "w") as f:
            json.dump(d, f)
    with open(ref_file) as f:
        ref = [p["illuminance"] for p in json.load(f)["points"]]
    print("| rays | hit records | seconds (hit stage) | mean error | each seed's mean signed error |")
    print("|---|---|---|---|---|")
    for rays in [int(x) for x in a.rays.split(",")]:
        for name, extra_env in CONFIGS.items():
            env = dict(os.environ, ORC_TIME="1", **extra_env)
            errs, signed, secs, hits, hs = [], [], [], [], []
            for seed in range(1, a.seeds + 1):
                d, h = run(a.irrcache, scene, ["--seed", str(seed), "--rays", str(rays),
                                               "--light-samples", str(max(256, rays // 4))], env)
                vals = [p["illuminance"] for p in d["points"]]
                rel = [(v - r) / r for v, r in zip(vals, ref)]
                errs.append(statistics.fmean(abs(x) for x in rel))
                signed.append(statistics.fmean(rel))
                secs.append(d["seconds"])
                hits.append(d["hit_records"])
                hs.append(h)
            print("| %d, %s | %d | %.3f (%.3f) | %.2f %% | %s |" % (
                rays, name, statistics.fmean(hits), statistics.median(secs), statistics.median(hs),
                100 * statistics.fmean(errs), " ".join("%+.2f" % (100 * s) for s in signed)), flush=True)


if __name__ == "__main__":
    main()
