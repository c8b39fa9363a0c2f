#!/usr/bin/env python3
"""rad_load.py: how long a Radiance scene with many materials takes to load (BENCHMARKS.md).

    python3 bench/rad_load.py --irrcache build/irrcache [--also NAME=EXE] [--materials 1,1000,5000]
                              [--polygons 200000] [--repeats 3]

Writes, for each count of materials M, a .rad file of M plastics (each its own reflectance) and a light
above a floor of --polygons small squares that use the materials in turn, then times `irrcache points` at
one upward sensor with one light sample and the path tracer's 16 paths (so the time is the scene's load
and the points' setup; each run's wall time, the best of --repeats). With --also the same files go to other
builds, run alternately with the first.
"""
import argparse
import os
import subprocess
import tempfile
import time


def write_scene(path, materials, polygons):
    side = int(polygons ** 0.5) + 1
    with open(path, "w") as f:
        f.write("void light lamp\n0\n0\n3 10 10 10\n")
        f.write("lamp polygon ceiling\n0\n0\n12 0 0 4  %d 0 4  %d %d 4  0 %d 4\n" % (side, side, side, side))
        for m in range(materials):
            r = 0.2 + 0.6 * (m % 97) / 96.0
            f.write("void plastic m%d\n0\n0\n5 %.4f %.4f %.4f 0 0\n" % (m, r, r, r))
        for k in range(polygons):
            x, y = k % side, k // side
            f.write("m%d polygon p%d\n0\n0\n12 %d %d 0  %d %d 0  %d %d 0  %d %d 0\n" % (
                k % materials, k, x, y, x + 1, y, x + 1, y + 1, x, y + 1))
    return side


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--irrcache", required=True)
    ap.add_argument("--also", action="append", default=[], help="NAME=EXE: another build, run alternately")
    ap.add_argument("--materials", default="1,1000,5000")
    ap.add_argument("--polygons", type=int, default=200000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    builds = [("this", args.irrcache)] + [tuple(a.split("=", 1)) for a in args.also]
    with tempfile.TemporaryDirectory() as tmp:
        for m in [int(v) for v in args.materials.split(",")]:
            scene = os.path.join(tmp, "m%d.rad" % m)
            side = write_scene(scene, m, args.polygons)
            pts = os.path.join(tmp, "p.txt")
            with open(pts, "w") as f:
                f.write("%g %g 1 0 0 1\n" % (side / 2.0, side / 2.0))
            best = {name: float("inf") for name, _ in builds}
            for _ in range(args.repeats):
                for name, exe in builds:
                    t0 = time.perf_counter()
                    subprocess.run([exe, "points", scene, "--points", pts, "--integrator", "pt", "--samples", "16",
                                    "-q"], check=True, stdout=subprocess.DEVNULL)
                    best[name] = min(best[name], time.perf_counter() - t0)
            print("materials %6d  polygons %d  " % (m, args.polygons) +
                  "  ".join("%s %.2f s" % (name, best[name]) for name, _ in builds))


if __name__ == "__main__":
    main()
