#!/usr/bin/env python3
"""bench/mpi_model.py: what the runs of bench/mpi.sh measured, and a model of a render shared by N ranks.

    python3 bench/mpi_model.py RUNS_DIR [--target STATS.json] [--ranks 4 16 64] [--links 1 10]

Part 1 (measured, RUNS_DIR): the median seconds of each phase for 1 rank x 2 threads and 2 ranks x 1
thread (runs alternated by bench/mpi.sh), their ratio, and rank 0's communication per construction pass
(seconds, bytes) in the 2-rank runs. From the 1 rank x 1 thread run, the share of the "candidates" phase
that does not divide among ranks: c(2 ranks) = s + p/2 and c(1) = s + p give s = 2 c(2) - c(1).

Part 2 (model, --target: the stats of a one-process render of the scene at the size that matters, e.g.
Sponza at 1280x720). Each phase is either shared (gathering, the final render, the shared part of
candidates) or done by every rank (loading, the accelerator, shading points, insertion, the record
filter, the rest of candidates). With N ranks of the same threads:

    T_N = serial + shared / N x imbalance(N) + communication(N)

  - records: every pass's records are all-gathered; each rank receives (N-1)/N of
    n_p x RECORD_BYTES (the gather result, 184 bytes, and the bounce levels, 12 bytes x (levels + 1));
  - candidates and look-up sweeps: the bytes the 2-rank runs measured beyond the records, scaled by the
    pixel count and by (N-1)/N against 1/2;
  - the image: the adaptive pilot's sums (4 doubles per pixel) and the image (3 doubles) added over the
    ranks, 2 (N-1)/N of each per rank (a ring all-reduce);
  - latency: every collective as N - 1 ring steps of ALPHA (50 us at 1 Gb/s, 20 us at 10 Gb/s), about
    12 collectives per pass;
  - imbalance: the 2-rank runs' gathering against half the 1-rank x 1-thread gathering gives I(2); the
    excess grows like the expected maximum of N blocks, sqrt(2 ln N) / sqrt(2 ln 2).

Efficiency E(N) = T_1 / (N T_N). Python 3 standard library only.
"""

import argparse
import glob
import json
import math
import os
import statistics

RESULT_BYTES = 184  # sizeof(ic_gather_result)
LEVEL_BYTES = 12    # one RGB level (ic_vec3)
COLLECTIVES_PER_PASS = 12
ALPHA = {1: 50e-6, 10: 20e-6}


def load(path):
    with open(path) as f:
        return json.load(f)


def phase(d, name):
    return d["phases"].get(name, 0.0)


def median_phases(runs):
    names = []
    for d in runs:
        for n in d["phases"]:
            if n not in names:
                names.append(n)
    out = {n: statistics.median(phase(d, n) for d in runs) for n in names}
    out["total"] = statistics.median(d["seconds"] for d in runs)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs")
    ap.add_argument("--target", help="stats of a one-process render at the size the model is for")
    ap.add_argument("--ranks", type=int, nargs="+", default=[4, 16, 64])
    ap.add_argument("--links", type=int, nargs="+", default=[1, 10], help="link speeds, Gb/s")
    ap.add_argument("--max-depth", type=int, default=8, help="the renders' --max-depth (levels = max-depth - 1)")
    a = ap.parse_args()

    one = [load(p) for p in sorted(glob.glob(os.path.join(a.runs, "1x2-*.json")))]
    two = [load(p) for p in sorted(glob.glob(os.path.join(a.runs, "2x1-*.json")))]
    single = load(os.path.join(a.runs, "1x1.json"))
    m1, m2 = median_phases(one), median_phases(two)
    print("## measured: %s, %dx%d, %d records, %d passes" % (one[0]["scene"], one[0]["width"], one[0]["height"],
                                                             one[0]["records"], one[0]["passes"]))
    print("| phase | 1 rank x 2 threads (s) | 2 ranks x 1 thread (s) | ratio | 1 rank x 1 thread (s) |")
    print("|---|---|---|---|---|")
    for n in list(m1):
        print("| %s | %.2f | %.2f | %.2f | %.2f |" % (n, m1[n], m2.get(n, 0.0), m2.get(n, 0.0) / m1[n] if m1[n] else 0,
                                                  single["seconds"] if n == "total" else phase(single, n)))
    ranks = two[0]["per_rank"]
    print("\ncommunication, 2 ranks (median run's rank 0 / rank 1): %.2f / %.2f s, %.2f / %.2f MB in all"
          % (ranks[0]["comm_seconds"], ranks[1]["comm_seconds"], ranks[0]["comm_bytes"] / 1e6,
             ranks[1]["comm_bytes"] / 1e6))
    print("records gathered per rank: %s; pixel samples per rank: %s"
          % ([r["records_gathered"] for r in ranks], [r["pixel_samples"] for r in ranks]))
    print("\n| pass | records | rank 0 comm (ms) | rank 0 received (kB) |")
    print("|---|---|---|---|")
    per_pass_s = ranks[0].get("comm_seconds_per_pass", [])
    per_pass_b = ranks[0].get("comm_bytes_per_pass", [])
    for p, n in enumerate(two[0]["records_per_pass"]):
        print("| %d | %d | %.1f | %.1f |" % (p, n, 1e3 * per_pass_s[p], per_pass_b[p] / 1e3))

    record_bytes = RESULT_BYTES + LEVEL_BYTES * a.max_depth
    # The candidates phase: s + p from one thread, s + p / 2 from two ranks.
    c1, c2 = phase(single, "candidates"), m2["candidates"]
    cand_serial = min(max(2 * c2 - c1, 0.0) / c1, 1.0) if c1 > 0 else 1.0
    g1, g2 = phase(single, "gathering"), m2["gathering"]
    imbalance2 = max(g2 / (g1 / 2), 1.0) if g1 > 0 else 1.0
    f1, f2 = phase(single, "final render"), m2["final render"]
    final_imbalance2 = max(f2 / (f1 / 2), 1.0) if f1 > 0 else 1.0
    rec_bytes_2 = sum(two[0]["records_per_pass"]) * record_bytes / 2
    pass_bytes_2 = sum(per_pass_b)
    other_bytes_2 = max(pass_bytes_2 - rec_bytes_2, 0.0)
    print("\nrecord: %d bytes exchanged; candidates phase not shared: %.0f %% (c = %.2f s at 1 rank x 1 thread, "
          "%.2f s at 2 ranks x 1 thread); imbalance at 2 ranks: gathering %.2f, final render %.2f (waiting "
          "included); bytes per rank beyond the records: %.2f MB"
          % (record_bytes, 100 * cand_serial, c1, c2, imbalance2, final_imbalance2, other_bytes_2 / 1e6))

    if not a.target:
        return
    t = load(a.target)
    px = t["width"] * t["height"]
    px_ratio = px / (one[0]["width"] * one[0]["height"])
    shared = {"gathering": phase(t, "gathering"), "final render": phase(t, "final render"),
              "candidates": phase(t, "candidates") * (1 - cand_serial)}
    total_1 = t["seconds"]
    serial = total_1 - sum(shared.values())
    records = sum(t["records_per_pass"])
    print("\n## model: %s at %dx%d, %d threads per rank: %.0f s in one process (%d records, %d passes); "
          "shared %.0f s (gathering %.0f, final render %.0f, candidates %.0f), every rank %.1f s"
          % (t["scene"], t["width"], t["height"], t["threads"], total_1, records, t["passes"],
             sum(shared.values()), shared["gathering"], shared["final render"], shared["candidates"], serial))
    print("| ranks | link | received per rank (MB) | communication (s) | T_N (s) | speed-up | efficiency |")
    print("|---|---|---|---|---|---|---|")
    for n in a.ranks:
        grow = math.sqrt(2 * math.log(n)) / math.sqrt(2 * math.log(2))
        imb_g = 1 + (imbalance2 - 1) * grow
        imb_f = 1 + (final_imbalance2 - 1) * grow
        share = (n - 1) / n
        volume = (records * record_bytes * share + other_bytes_2 * px_ratio * share / 0.5 +
                  px * (4 + 3) * 8 * 2 * share)
        for gbps in a.links:
            latency = COLLECTIVES_PER_PASS * t["passes"] * (n - 1) * ALPHA[gbps]
            comm = volume * 8 / (gbps * 1e9) + latency
            tn = (serial + (shared["gathering"] + shared["candidates"]) / n * imb_g + shared["final render"] / n * imb_f
                  + comm)
            print("| %d | %d Gb/s | %.1f | %.2f | %.1f | %.1f | %.2f |"
                  % (n, gbps, volume / 1e6, comm, tn, total_1 / tn, total_1 / (n * tn)))


if __name__ == "__main__":
    main()
