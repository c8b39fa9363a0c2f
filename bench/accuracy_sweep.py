#!/usr/bin/env python3
"""bench/accuracy_sweep.py: records, time and error of cache configurations as curves over the accuracy,
and records at equal error against the best split-sphere curve (issue 17's benchmark).

    python3 bench/accuracy_sweep.py SCENE [--width 160 --height 160] [--ref-spp 16384]
        --config NAME="irrcache options" [--config ...] [--accuracies 0.4,0.3,...] [--accuracies NAME=LIST]
        [--variant NAME="options" ...] [--seeds 1,2,3] [--baseline NAME ...] [--refs DIR] [--out DIR] [--csv FILE]
        [--md FILE] [--irrcache BIN] [--force] [-- options for every render]

Every configuration renders the scene with `--integrator ic --accuracy A` for each accuracy A of its list,
once per variant (by default two: `default`, the cache's own radius clamps, and `lifted`, the world-space and
pixel upper bounds lifted with `--max-radius 1e6 --max-radius-px 200`, which bind most records otherwise).
Each image is compared with `irrcache diff --json` against a path-traced reference, rendered once as two
halves with independent seeds and cached in --refs exactly as bench/equal_time.py does (same file names, so
the two share references); the reference's own noise (a quarter of the halves' relMSE against each other,
and the same for the low-pass relMSE) is printed beside the errors and should be well below them.

With --seeds every point is rendered once per seed and its row is the mean (records, seconds, errors):
a single seed's low-pass error varies by about ±15 % on the Cornell box at 160×160 (BENCHMARKS.md).

"Records" are the image's own, which the criterion places: the hit records (the batch strategy's records
where hemisphere rays land, `--hit-records`, placed by the hits and not by the error metric) are counted
apart. For each point the table gives the accuracy, records, seconds, rays, relMSE and low-pass relMSE, and two
ratios against the baselines (`--baseline`, default `ward` and `tl`: the split-sphere criteria): the records
the best baseline needs for the same error, interpolated log-log along its lower envelope (the fewest
records reaching at most that error), divided into this point's records (below 1: fewer records than the
best split-sphere setting), once for relMSE and once for the low-pass relMSE; the same for seconds (wall
time on a possibly shared machine: compare within one run); "-" where the error lies outside the
baseline's range (no extrapolation). The other reading of the same curves, the error gain: the error the
best baseline's envelope reaches with as many records as this point has, divided by this point's error
(above 1: less error at equal records), once for each error; "-" where the records lie outside the
baseline's range. The issue's goal is a records ratio of at most 0.5, or an error gain of at least 4, on
two of three scenes.

Runs are cached in --out (a JSON line per run, keyed by the render's arguments and the reference, and
valid for the binary that made them, or for any with --any-binary), so adding a configuration later
renders only the new one (`--force` renders again).
One render at a time; Python 3 standard library only.
"""

import argparse
import hashlib
import json
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.dont_write_bytecode = True
sys.path.insert(0, HERE)

import equal_time  # noqa: E402  (the shared reference and diff helpers)

DEFAULT_ACCURACIES = "0.5,0.4,0.3,0.2,0.15,0.1,0.07"
# Tabellion-Lamorlette's accuracy is on another scale (its default is 1 against Ward's 0.15).
DEFAULT_ACCURACIES_TL = "3,2.5,2,1.5,1,0.7,0.5"
DEFAULT_VARIANTS = ["default=", "lifted=--max-radius 1e6 --max-radius-px 200"]


def split_pair(text, what):
    if "=" not in text:
        raise SystemExit("accuracy_sweep: %s %r must be NAME=VALUE" % (what, text))
    name, value = text.split("=", 1)
    return name.strip(), value.strip()


def file_digest(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()[:16]


def envelope(points):
    """Lower envelope of (records, error) points: sorted by records, each with less error than all before."""
    front = []
    for rec, err in sorted(points):
        if err > 0 and (not front or err < front[-1][1]):
            front.append((rec, err))
    return front


def log_interp(points, x):
    """y at x along points (x, y) sorted by x, log-log between neighbours; None outside their range."""
    if not points or x < points[0][0] or x > points[-1][0]:
        return None
    for (x0, y0), (x1, y1) in zip(points, points[1:]):
        if x0 <= x <= x1:
            t = (math.log(x) - math.log(x0)) / (math.log(x1) - math.log(x0)) if x1 > x0 else 0.0
            return math.exp(math.log(y0) + t * (math.log(y1) - math.log(y0)))
    return points[0][1]  # a single point hit exactly


def records_at(front, err):
    """Records (or seconds) the envelope needs to reach error `err` (log-log interpolation); None outside its range."""
    return log_interp([(e, r) for r, e in reversed(front)], err)


def error_at(front, records):
    """The error the envelope reaches with `records` records (log-log interpolation); None outside its range."""
    return log_interp(front, records)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], epilog="-- then options for every render")
    ap.add_argument("scene")
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=160)
    ap.add_argument("--ref-spp", type=int, default=16384)
    ap.add_argument("--config", action="append", default=[], metavar="NAME=OPTIONS",
                    help="a configuration: its name and its irrcache render options (repeat)")
    ap.add_argument("--accuracies", action="append", default=[], metavar="[NAME=]LIST",
                    help="comma-separated accuracies for every configuration, or NAME=LIST for one "
                         "(default %s; %s for a configuration with --weight tl)" % (DEFAULT_ACCURACIES,
                                                                                  DEFAULT_ACCURACIES_TL))
    ap.add_argument("--variant", action="append", default=[], metavar="NAME=OPTIONS",
                    help="options added to every configuration, one sweep per variant (default: %s)" %
                         " and ".join(repr(v) for v in DEFAULT_VARIANTS))
    ap.add_argument("--seeds", help="comma-separated --seed values; each point is the mean over them "
                                    "(default: the scene's own seed, one render per point)")
    ap.add_argument("--baseline", action="append", default=[],
                    help="configurations the ratios compare against (default: ward and tl, where given)")
    ap.add_argument("--refs", default=os.path.join(HERE, "cache", "equal-time"))
    ap.add_argument("--out", default=os.path.join(HERE, "out", "accuracy-sweep"))
    ap.add_argument("--csv", help="write the table as CSV here")
    ap.add_argument("--md", help="write the table as Markdown here")
    ap.add_argument("--irrcache", default=os.path.join(ROOT, "build", "irrcache"))
    ap.add_argument("--force", action="store_true", help="render again even where a run is cached")
    ap.add_argument("--any-binary", action="store_true",
                    help="reuse cached runs made by another build of irrcache (when its change is known to leave "
                         "them alone, e.g. a new configuration's option); by default they render again")
    argv = sys.argv[1:]
    cut = argv.index("--") if "--" in argv else len(argv)
    args = ap.parse_args(argv[:cut])
    common = argv[cut + 1:]
    if not args.config:
        raise SystemExit("accuracy_sweep: give at least one --config NAME=OPTIONS")
    configs = [split_pair(c, "--config") for c in args.config]
    names = [n for n, _ in configs]
    default_acc, per_config = None, {}
    for a in args.accuracies:
        if "=" in a:
            n, v = split_pair(a, "--accuracies")
            per_config[n] = v
        else:
            default_acc = a
    variants = [split_pair(v, "--variant") for v in (args.variant or DEFAULT_VARIANTS)]
    seeds = [x.strip() for x in args.seeds.split(",") if x.strip()] if args.seeds else [None]
    baselines = args.baseline or [n for n in ("ward", "tl") if n in names]

    os.makedirs(args.refs, exist_ok=True)
    os.makedirs(args.out, exist_ok=True)
    ref, noise = equal_time.reference(args)
    ref_key = os.path.basename(ref)
    binary_key = file_digest(args.irrcache)
    scene_name = os.path.splitext(os.path.basename(args.scene))[0]
    cache_path = os.path.join(args.out, "%s-%dx%d.jsonl" % (scene_name, args.width, args.height))
    cached = {}
    if os.path.exists(cache_path):
        with open(cache_path) as f:
            for line in f:
                if line.strip():
                    rec = json.loads(line)
                    cached[rec["key"]] = rec
    print("%s %dx%d: reference %d spp, its noise relMSE %.2g, low-pass %.2g" % (
        scene_name, args.width, args.height, args.ref_spp, noise["relmse"], noise["relmse_lowpass"]), flush=True)

    rows = []
    for vname, vopts in variants:
        for cname, copts in configs:
            copt_list = copts.split()
            fallback = DEFAULT_ACCURACIES_TL if "tl" in copt_list and "--weight" in copt_list else DEFAULT_ACCURACIES
            accs = [float(x) for x in per_config.get(cname, default_acc or fallback).split(",") if x.strip()]
            for acc in accs:
                base = ["--width", str(args.width), "--height", str(args.height), "--accuracy", repr(acc)] + \
                    copt_list + vopts.split() + common
                runs = []
                for seed in seeds:
                    opts = base + (["--seed", seed] if seed else [])
                    key = hashlib.sha256(json.dumps([args.scene, opts, ref_key]).encode()).hexdigest()[:20]
                    rec = None if args.force else cached.get(key)
                    if rec is not None and rec.get("binary") != binary_key and not args.any_binary:
                        rec = None
                    if rec is not None and "hit_records" not in rec:  # cached before image records were apart
                        rec = None
                    if rec is None:
                        stem = os.path.join(args.out, "%s-%s-%s-%g%s" % (scene_name, vname, cname, acc,
                                                                          "-s" + seed if seed else ""))
                        subprocess.run([args.irrcache, "render", args.scene, "--integrator", "ic", "-q", "-o",
                                        stem + ".pfm", "--stats", stem + ".json"] + opts, check=True)
                        with open(stem + ".json") as f:
                            stats = json.load(f)
                        d = equal_time.diff(args.irrcache, stem + ".pfm", ref)
                        rec = {"key": key, "binary": binary_key, "scene": args.scene, "variant": vname,
                               "config": cname, "accuracy": acc, "options": opts,
                               "records": stats.get("records", 0) - stats.get("hit_records", 0),
                               "hit_records": stats.get("hit_records", 0), "seconds": stats["seconds"],
                               "rays": stats["rays"], "relmse": d["relmse"], "relmse_lowpass": d["relmse_lowpass"],
                               "reference_noise": noise}
                        with open(cache_path, "a") as f:
                            f.write(json.dumps(rec) + "\n")
                        cached[key] = rec
                    runs.append(rec)
                # One row per point: the mean over the seeds.
                row = {"variant": vname, "config": cname, "accuracy": acc, "seeds": len(runs)}
                for field in ("records", "hit_records", "seconds", "rays", "relmse", "relmse_lowpass"):
                    row[field] = sum(r[field] for r in runs) / len(runs)
                rows.append(row)
                print("%-8s %-10s a=%-6g %7.0f records (+%.0f hit records) %7.2f s  relMSE %.3g  low-pass %.3g" % (
                    vname, cname, acc, row["records"], row["hit_records"], row["seconds"], row["relmse"],
                    row["relmse_lowpass"]),
                    flush=True)

    # Ratios against the best baseline of the same variant: records (and seconds) the baseline's lower
    # envelope needs for the same error.
    for row in rows:
        for what in ("records", "seconds"):
            for metric in ("relmse", "relmse_lowpass"):
                need = []
                for b in baselines:
                    front = envelope([(r[what], r[metric]) for r in rows
                                      if r["variant"] == row["variant"] and r["config"] == b])
                    n = records_at(front, row[metric])
                    if n is not None:
                        need.append(n)
                row["%s_ratio_%s" % (what, metric)] = row[what] / min(need) if need else None
        # The other reading of the same curves: the best baseline's error with as many records, divided by
        # this point's (above 1: less error than the best split-sphere setting at equal records).
        for metric in ("relmse", "relmse_lowpass"):
            have = []
            for b in baselines:
                front = envelope([(r["records"], r[metric]) for r in rows
                                  if r["variant"] == row["variant"] and r["config"] == b])
                e = error_at(front, row["records"])
                if e is not None:
                    have.append(e)
            row["gain_%s" % metric] = min(have) / row[metric] if have and row[metric] > 0 else None

    def fmt(x, f):
        return "-" if x is None else f % x

    header = ["variant", "config", "accuracy", "records", "seconds", "rays", "relmse", "relmse_lowpass",
              "records_ratio_relmse", "records_ratio_lowpass", "seconds_ratio_relmse", "seconds_ratio_lowpass",
              "error_gain_relmse", "error_gain_lowpass"]
    lines = []
    for r in rows:
        lines.append([r["variant"], r["config"], "%g" % r["accuracy"], "%.0f" % r["records"], "%.2f" % r["seconds"],
                      "%.0f" % r["rays"], "%.3g" % r["relmse"], "%.3g" % r["relmse_lowpass"],
                      fmt(r["records_ratio_relmse"], "%.2f"), fmt(r["records_ratio_relmse_lowpass"], "%.2f"),
                      fmt(r["seconds_ratio_relmse"], "%.2f"), fmt(r["seconds_ratio_relmse_lowpass"], "%.2f"),
                      fmt(r["gain_relmse"], "%.2f"), fmt(r["gain_relmse_lowpass"], "%.2f")])
    print()
    print("baselines (records ratio = records / the best baseline's records at equal error; error gain = the best "
          "baseline's error at equal records / this error): %s" % ", ".join(baselines))
    widths = [max(len(h), *(len(l[i]) for l in lines)) for i, h in enumerate(header)]
    for l in [header] + lines:
        print("  ".join(c.rjust(w) for c, w in zip(l, widths)))
    if args.csv:
        tmp = args.csv + ".tmp"
        with open(tmp, "w") as f:
            f.write(",".join(header) + "\n")
            for l in lines:
                f.write(",".join(c if c != "-" else "" for c in l) + "\n")
        os.replace(tmp, args.csv)
    if args.md:
        tmp = args.md + ".tmp"
        with open(tmp, "w") as f:
            f.write("| variant | config | a | records | s | relMSE | low-pass | records / best split sphere's "
                    "at equal relMSE, low-pass | seconds / its, at equal low-pass | its relMSE, low-pass at equal "
                    "records / this one's |\n|---|---|---|---|---|---|---|---|---|---|\n")
            for l in lines:
                f.write("| %s | %s | %s | %s | %s | %s | %s | %s, %s | %s | %s, %s |\n" % (
                    l[0], l[1], l[2], l[3], l[4], l[6], l[7], l[8], l[9], l[11], l[12], l[13]))
        os.replace(tmp, args.md)


if __name__ == "__main__":
    sys.exit(main())
