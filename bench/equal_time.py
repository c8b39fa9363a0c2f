#!/usr/bin/env python3
"""bench/equal_time.py: one cache configuration against the path tracer given the same wall time, on one
scene, measured against a path-traced reference whose own noise is reported beside the errors.

    python3 bench/equal_time.py SCENE [--width 320 --height 240] [--ref-spp 4096] [--name NAME]
                                [--refs DIR] [--irrcache BIN] [--no-pt] -- [irrcache render options]

The reference is rendered once (cached in --refs, keyed by the scene file's bytes, the size and the
sample count) as two halves with independent seeds; its relMSE against the truth is about a quarter of
the halves' relMSE against each other, and that figure is printed as the reference's noise (relMSE and
low-pass relMSE); the ratio of the two errors is also printed with that noise taken off both (their errors
against the truth, since the reference's noise is independent of theirs). Then the cache renders with the given options (`--integrator ic` is added), and the
path tracer renders with `--time` set to the cache render's own `seconds` from its stats (`--equal time`,
the default) or with the sample count that spends as many rays as the cache render did (`--equal rays`:
independent of the machine's load, so runs on a shared machine compare; the path tracer's rays per sample
come from a 4-spp pilot render, cached in --refs). Both are compared with `irrcache diff --json`. One line per run, and a JSON record with --json-out. Python 3
standard library only. Used for the record-noise-control figures in BENCHMARKS.md.
"""

import argparse
import hashlib
import json
import os
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def read_pfm(path):
    with open(path, "rb") as f:
        f.readline()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        n = w * h * 3
        data = f.read(4 * n)
    return w, h, struct.unpack(("<" if scale < 0 else ">") + "%df" % n, data)


def write_pfm(path, w, h, values):
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        f.write(struct.pack("<%df" % len(values), *values))
    os.replace(tmp, path)


def diff(binary, image, ref):
    out = subprocess.run([binary, "diff", image, ref, "--json"], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def reference(args):
    """Path of the averaged reference and the reference's noise (relMSE, low-pass relMSE)."""
    with open(args.scene, "rb") as f:
        key = hashlib.sha256(f.read() + b"%d %d %d" % (args.width, args.height, args.ref_spp)).hexdigest()[:16]
    base = os.path.join(args.refs, "%s-%s" % (os.path.splitext(os.path.basename(args.scene))[0], key))
    halves = []
    for seed in (101, 202):
        path = "%s-%d.pfm" % (base, seed)
        if not os.path.exists(path):
            subprocess.run([args.irrcache, "render", args.scene, "--width", str(args.width), "--height",
                            str(args.height), "--spp", str(args.ref_spp // 2), "--adaptive-sampling", "off",
                            "--seed", str(seed), "-q", "-o", path], check=True)
        halves.append(path)
    ref = base + "-ref.pfm"
    noise_path = base + "-noise.json"
    if not os.path.exists(ref) or not os.path.exists(noise_path):
        w, h, a = read_pfm(halves[0])
        _, _, b = read_pfm(halves[1])
        write_pfm(ref, w, h, [(x + y) / 2 for x, y in zip(a, b)])
        d = diff(args.irrcache, halves[0], halves[1])
        with open(noise_path, "w") as f:
            json.dump({"relmse": d["relmse"] / 4, "relmse_lowpass": d["relmse_lowpass"] / 4}, f)
    with open(noise_path) as f:
        return ref, json.load(f)


def pt_rays_per_spp(args, size):
    """The path tracer's rays per sample at this size (a 4-spp pilot, cached beside the reference)."""
    with open(args.scene, "rb") as f:
        key = hashlib.sha256(f.read() + b"%d %d" % (args.width, args.height)).hexdigest()[:16]
    path = os.path.join(args.refs, "%s-%s-pt-rays.json" % (os.path.splitext(os.path.basename(args.scene))[0], key))
    if not os.path.exists(path):
        stats = path + ".stats.json"
        subprocess.run([args.irrcache, "render", args.scene, "-q", "--spp", "4", "-o", path + ".pfm", "--stats",
                        stats] + size, check=True)
        with open(stats) as f:
            rays = json.load(f)["rays"] / 4.0
        os.remove(stats)
        os.remove(path + ".pfm")
        with open(path, "w") as f:
            json.dump({"rays_per_spp": rays}, f)
    with open(path) as f:
        return json.load(f)["rays_per_spp"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], epilog="-- then irrcache render options")
    ap.add_argument("scene")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--name", default="ic")
    ap.add_argument("--refs", default=os.path.join(HERE, "cache", "equal-time"))
    ap.add_argument("--out", default=os.path.join(HERE, "out", "equal-time"))
    ap.add_argument("--irrcache", default=os.path.join(ROOT, "build", "irrcache"))
    ap.add_argument("--no-pt", action="store_true", help="skip the equal-time path tracer")
    ap.add_argument("--equal", choices=("time", "rays"), default="time",
                    help="give the path tracer the cache render's seconds (time) or its ray count (rays)")
    ap.add_argument("--json-out", help="append the run's record to this JSON-lines file")
    argv = sys.argv[1:]
    cut = argv.index("--") if "--" in argv else len(argv)
    args = ap.parse_args(argv[:cut])
    opts = argv[cut + 1:]  # after "--": irrcache render options
    # Options this script sets itself: given again after "--" they would silently take over (the CLI
    # keeps the last), e.g. a second --stats left this script reading an older run's statistics.
    managed = ("--stats", "-o", "--output", "--integrator", "--width", "--height")
    clash = [o for o in opts if o.split("=")[0] in managed]
    if clash:
        ap.error("%s after \"--\": this script sets it (use --width/--height before \"--\"; the statistics "
                 "are in --out)" % clash[0])
    os.makedirs(args.refs, exist_ok=True)
    os.makedirs(args.out, exist_ok=True)
    ref, noise = reference(args)
    stem = os.path.join(args.out, "%s-%s" % (os.path.splitext(os.path.basename(args.scene))[0], args.name))
    size = ["--width", str(args.width), "--height", str(args.height)]
    for stale in (stem + ".json", stem + "-pt.json"):  # a failed run must not leave an older one's figures
        if os.path.exists(stale):
            os.remove(stale)
    subprocess.run([args.irrcache, "render", args.scene, "--integrator", "ic", "-q", "-o", stem + ".pfm", "-o",
                    stem + ".png", "--stats", stem + ".json"] + size + opts, check=True)
    with open(stem + ".json") as f:
        stats = json.load(f)
    rec = {"scene": args.scene, "name": args.name, "options": opts, "seconds": stats["seconds"],
           "records": stats.get("records"), "reference_noise": noise, "ic": diff(args.irrcache, stem + ".pfm", ref)}
    rec["rays"] = stats["rays"]
    if not args.no_pt:
        budget = ["--time", "%.3f" % stats["seconds"], "--spp", "16777216"]
        if args.equal == "rays":
            spp = max(1, round(stats["rays"] / pt_rays_per_spp(args, size)))
            budget = ["--spp", str(spp)]
            rec["pt_spp"] = spp
        subprocess.run([args.irrcache, "render", args.scene, "-q", "-o", stem + "-pt.pfm", "-o", stem + "-pt.png",
                        "--stats", stem + "-pt.json"] + budget + size, check=True)
        with open(stem + "-pt.json") as f:
            pt_stats = json.load(f)
        rec["pt_seconds"], rec["pt_rays"] = pt_stats["seconds"], pt_stats["rays"]
        rec["pt"] = diff(args.irrcache, stem + "-pt.pfm", ref)
    ic, pt = rec["ic"], rec.get("pt")
    line = "%-12s %-16s %7.2f s %6.1f Mrays %6s records | cache relMSE %.3g low-pass %.3g" % (
        os.path.splitext(os.path.basename(args.scene))[0], args.name, rec["seconds"], rec["rays"] / 1e6,
        rec["records"], ic["relmse"], ic["relmse_lowpass"])
    if pt and args.equal == "rays":
        line += " | path tracer %d spp, %.2f s" % (rec["pt_spp"], rec["pt_seconds"])
    if pt:
        line += " | path tracer relMSE %.3g low-pass %.3g | ratio %.2f, low-pass %.2f" % (
            pt["relmse"], pt["relmse_lowpass"], pt["relmse"] / ic["relmse"], pt["relmse_lowpass"] / ic["relmse_lowpass"])
        # Each image's error against the reference holds the reference's own noise besides its own (they
        # are independent): taken off both, the ratio of the two images' errors against the truth.
        if ic["relmse"] > noise["relmse"]:
            rec["ratio_less_noise"] = (pt["relmse"] - noise["relmse"]) / (ic["relmse"] - noise["relmse"])
            line += " (%.2f less the reference's noise)" % rec["ratio_less_noise"]
    line += " | reference noise %.2g, low-pass %.2g" % (noise["relmse"], noise["relmse_lowpass"])
    print(line, flush=True)
    if args.json_out:
        with open(args.json_out, "a") as f:
            f.write(json.dumps(rec) + "\n")


if __name__ == "__main__":
    sys.exit(main())
