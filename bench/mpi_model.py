#!/usr/bin/env python3
"""bench/mpi_model.py: what the runs of bench/mpi.sh measured, and a model of a render shared by N ranks.

    python3 bench/mpi_model.py RUNS_DIR [--target STATS.json] [--measured STATS_N.json [--trace TRACE_N]]
                               [--candidates-serial F] [--record-cv CV] [--tile-cv CV] [--ranks 4 16 64] [--links 1 10]

Part 1 (measured, RUNS_DIR): the median seconds of each phase for 1 rank x 2 threads and 2 ranks x 1
thread (runs alternated by bench/mpi.sh), their ratio, and rank 0's communication per construction pass
(seconds, bytes) in the 2-rank runs.

Part 2 (model, --target: the stats of a one-process render of the scene at the size that matters, e.g.
Sponza at 1280x720). Each phase is either shared (gathering, the final render, the batch strategy's
"eye paths and look-ups": the world stage's eye paths and the look-up sweeps, "need maps", "clustering", the shading points, the
record filter, and insertion's validity-radius clamp and neighbour search, --insertion-shared of insertion) or done by every
rank (the accelerator, the rest of insertion, "candidates": clustering (and dithering before each rank dithered its own rows), and the need maps in
stats written before "need maps" was reported apart, and whatever ic_render spends outside its phases; with --with-load
also the scene load, which the stats' "seconds" leave out). Stats written before "eye paths and
look-ups" was reported apart count it in "candidates"; --candidates-serial then says which share of that
every rank does; every rank also computes the shading points of 128 rows around its own (the band its need
maps read), taken as that share of the "shading points" phase. With N ranks of the same threads:

    T_N = serial + shared / N x imbalance(N) + communication(N)

  - records: every pass's records are all-gathered; each rank receives (N-1)/N of
    n_p x RECORD_BYTES (the gather result less its Hessian and counts, 104 bytes, and the bounce levels, 12 bytes x
    (levels + 1));
  - candidates and look-up sweeps: the bytes the 2-rank runs measured beyond the records, scaled by the
    pixel count and by (N-1)/N against 1/2 (as all-gathers: since the world stage's candidates go to their
    Morton range's rank and the look-ups' luminance only to the ranks whose rows are near, both
    all-to-alls, this overstates them at more ranks; --measured replaces the whole estimate by the bytes
    of a real run);
  - whether each pixel has a shading point (1 byte a pixel: each rank computes the points of its rows and
    of a band around them, 29 bytes a pixel before) and the filtered records (88 bytes each), all-gathered
    once;
  - the image: the adaptive pilot's relative variances (1 double per pixel) and the image (3 floats),
    each rank's tiles all-gathered, (N-1)/N of each per rank, and the pilot's sums (3 doubles per pixel) of
    the tiles whose second pass leaves the rank that rendered their pilot (--tiles-moved of them);
    --film-doubles: the pilot's sums (4 doubles) and the image (3 doubles) as exchanged before; --sum-image:
    those added over the ranks as before that, 2 (N-1)/N of each, a ring all-reduce;
  - latency: rounds of messages of ALPHA each (50 us at 1 Gb/s, 20 us at 10 Gb/s), about 23 exchanges per
    pass (296 in the 13 passes of Sponza at 1280x720 and 16 ranks, IRRCACHE_MPI_TRACE, the hit stage's and
    the coverage sweeps' included): an all-gather up to 1 MiB in all takes Bruck's ceil(log2 N) rounds, the
    all-to-all (one a pass) and the 3 larger all-gathers of a render N - 1 (--ring: every exchange N - 1,
    the command's transport before Bruck's all-gather);
  - the film's variances and image stream during the pass that makes them (the pilot a quarter of the
    final render's time, the second pass the rest): only what outlasts that pass is charged (--film-doubles,
    --sum-image: exchanged after the passes, as before);
  - imbalance: a rank's share of a pass is m = n_p / N records (rounded up), and its cost the sum of m
    record costs of relative spread --record-cv (default: measured, see BENCHMARKS.md); the slowest of N
    ranks takes about 1 + cv z_N / sqrt(m) times the mean, z_N the expected maximum of N standard normal
    draws (computed; --sqrt2ln for the bound sqrt(2 ln N) used before), pass by pass;
    likewise for the adaptive pilot's tiles (m = tiles / N, --tile-cv). Interleaving (record i and tile t on
    rank i mod N, t mod N) makes neighbouring, alike-costing work land on different ranks, so the sums
    are near independent draws. The second adaptive pass (three quarters of the samples) is shared out by
    measured cost (longest first to the least loaded rank): its slowest rank is over the mean by at most
    one tile (--interleaved-final models it interleaved like the pilot).

With --trace (IRRCACHE_MPI_TRACE=FILE of the --measured run: every exchange rank 0 took part in, with the
bytes it received and the rounds of messages it took), the communication at that rank count is the
trace's instead of the estimate above: sum over exchanges of bytes / rate + rounds x ALPHA (a ring
all-gather or an all-to-all N - 1 rounds, Bruck's all-gather and the sums ceil(log2 N)), the bytes scaled
to the rank that received most (its stats), plus the finished tiles streamed during the final render
(the pilot's variances, then the image) where their transfer outlasts the pass that streams them (the
pilot a quarter of the final render's time, the second pass three quarters) and the last tile of each.

Efficiency E(N) = T_1 / (N T_N). Python 3 standard library only.
"""

import argparse
import glob
import json
import math
import os
import statistics

RESULT_BYTES = 104  # the bytes of ic_gather_result that travel: all but its ray and hit counts, convergence flag and 64 bytes of Hessian (180 in all)
LEVEL_BYTES = 12    # one RGB level (ic_vec3)
COLLECTIVES_PER_PASS = 23
LARGE_EXCHANGES = 3  # all-gathers above 1 MiB in a render (Sponza 1280x720: two of the world stage, the filtered records)
ALPHA = {1: 50e-6, 10: 20e-6}


def expected_max_normal(n):
    """E[max of n independent standard normal draws], by the midpoint rule over [-10, 10]."""
    h, total = 1e-3, 0.0
    for k in range(20000):
        x = -10 + (k + 0.5) * h
        pdf = math.exp(-0.5 * x * x) / math.sqrt(2 * math.pi)
        cdf = 0.5 * (1 + math.erf(x / math.sqrt(2)))
        total += x * n * pdf * cdf ** (n - 1) * h
    return total


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


def read_trace(path):
    """An IRRCACHE_MPI_TRACE file: lines OPERATION BYTES_RECEIVED ROUNDS. Messages (finished tiles streamed
    while the film renders) are counted apart; those before the sum that follows the adaptive pilot (the
    pilot's tile times) are the pilot's variances."""
    out = {"exchanges": 0, "rounds": 0, "bytes": 0, "streamed": 0, "streamed_pilot": 0}
    seen_message, pilot_over = False, False
    with open(path) as f:
        for line in f:
            op, nbytes, rounds = line.split()
            if op == "message":
                out["streamed"] += int(nbytes)
                if not pilot_over:
                    out["streamed_pilot"] += int(nbytes)
                seen_message = True
                continue
            if seen_message and op == "sum":
                pilot_over = True
            out["exchanges"] += 1
            out["rounds"] += int(rounds)
            out["bytes"] += int(nbytes)
    if not pilot_over:  # no adaptive pilot: every message was the image's
        out["streamed_pilot"] = 0
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs")
    ap.add_argument("--target", help="stats of a one-process render at the size the model is for")
    ap.add_argument("--ranks", type=int, nargs="+", default=[4, 16, 64])
    ap.add_argument("--links", type=int, nargs="+", default=[1, 10], help="link speeds, Gb/s")
    ap.add_argument("--max-depth", type=int, default=8, help="the renders' --max-depth (levels = max-depth - 1)")
    ap.add_argument("--candidates-serial", type=float, default=0.1,
                    help="share of the candidates phase every rank does alike (clustering)")
    ap.add_argument("--record-cv", type=float, default=0.22,
                    help="relative spread of one record's gathering cost (0.22 measured on Sponza, BENCHMARKS.md)")
    ap.add_argument("--insertion-shared", type=float, default=0.52,
                    help="share of insertion that the ranks divide (the validity clamp and neighbour clamping's "
                         "neighbour search: 0.52 on Sponza 1280x720 since the octree build's radix sort, 0.48-0.49 "
                         "before it; the validity clamp alone 0.32-0.38, and 0.28 before the octrees and the frozen "
                         "layout were built on the threads; BENCHMARKS.md)")
    ap.add_argument("--sqrt2ln", action="store_true", help="the slowest rank's excess from the bound sqrt(2 ln N)")
    ap.add_argument("--tiles-moved", type=float, default=0.014,
                    help="share of the tiles whose adaptive second pass leaves the rank of their pilot (0.014 for "
                         "Sponza 1280x720 at 16 ranks, from its measured tile costs; BENCHMARKS.md)")
    ap.add_argument("--film-doubles", action="store_true",
                    help="model the film's exchanges as before: the pilot's sums and the image all-gathered as doubles")
    ap.add_argument("--sum-image", action="store_true", help="model the image added over the ranks (all-reduce)")
    ap.add_argument("--collectives", type=int, default=COLLECTIVES_PER_PASS,
                    help="exchanges per construction pass (%d, from a trace; 17 counted by hand before the hit "
                         "stage's and coverage sweeps' passes were seen)" % COLLECTIVES_PER_PASS)
    ap.add_argument("--ring", action="store_true", help="every exchange as N - 1 rounds (before Bruck's all-gather)")
    ap.add_argument("--tile-cv", type=float, default=1.0, help="relative spread of one tile's final-render cost")
    ap.add_argument("--measured", action="append", default=[], metavar="STATS.json",
                    help="the stats of a real N-rank run of the target (mpirun --oversubscribe on one machine "
                         "will do: bytes do not depend on the machine): its largest per-rank received bytes "
                         "stand in for the model's at N ranks")
    ap.add_argument("--interleaved-final", action="store_true",
                    help="model the final render's tiles all interleaved (before the second adaptive pass was "
                         "shared out by cost)")
    ap.add_argument("--with-load", action="store_true",
                    help="count the scene load (the \"load\" phase, outside the stats' seconds) in T_1 and in the work "
                         "every rank does alike (every rank loads the scene)")
    ap.add_argument("--trace", metavar="TRACE", help="IRRCACHE_MPI_TRACE of the real run given by --measured (its "
                    "rank count): rank 0's exchanges. The communication term at that rank count becomes the "
                    "trace's: every exchange's bytes at the link's rate plus its rounds of messages at the "
                    "link's latency, and the finished tiles streamed during the final render charged only "
                    "for what their pass's rendering does not cover")
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
    cand_serial = a.candidates_serial
    rec_bytes_2 = two[0]["records"] * record_bytes / 2
    pass_bytes_2 = sum(per_pass_b)
    other_bytes_2 = max(pass_bytes_2 - rec_bytes_2, 0.0)
    print("\nrecord: %d bytes exchanged; rank 0 received %.2f MB in the passes, %.2f MB of them beyond the "
          "records (candidates, look-up sweeps)" % (record_bytes, pass_bytes_2 / 1e6, other_bytes_2 / 1e6))

    if not a.target:
        return
    t = load(a.target)
    px = t["width"] * t["height"]
    px_ratio = px / (one[0]["width"] * one[0]["height"])
    if "eye paths and look-ups" in t["phases"]:
        shared_cand = phase(t, "eye paths and look-ups")
        cand_serial = phase(t, "candidates") / (phase(t, "candidates") + shared_cand)
    else:
        shared_cand = phase(t, "candidates") * (1 - cand_serial)
    shared = {"gathering": phase(t, "gathering"), "final render": phase(t, "final render"),
              "candidates": shared_cand + phase(t, "need maps") + phase(t, "clustering"),
              "points, filter, validity": phase(t, "shading points") + phase(t, "record filter") +
                                          a.insertion_shared * phase(t, "insertion")}
    # The stats' "seconds" are ic_render's: the scene load (phase "load", timed by the command) is outside them
    # and, unless --with-load, outside T_1 and T_N alike.
    total_1 = t["seconds"] + (phase(t, "load") if a.with_load else 0.0)
    serial = total_1 - sum(shared.values())
    # Every rank also computes the shading points of the band around its rows (IC_SCREEN_HALO, 64 rows on
    # either side) that its need maps read.
    band = phase(t, "shading points") * min(2 * 64, t["height"]) / t["height"]
    records = t["records"]
    print("\n## model: %s at %dx%d, %d threads per rank: %.0f s in one process (%d records, %d passes); "
          "shared %.1f s (gathering %.1f, final render %.1f, eye paths, look-ups and need maps %.1f, shading points, record "
          "filter, validity clamp and neighbour search %.2f), every rank %.2f s"
          % (t["scene"], t["width"], t["height"], t["threads"], total_1, records, t["passes"],
             sum(shared.values()), shared["gathering"], shared["final render"], shared["candidates"],
             shared["points, filter, validity"], serial))
    print("(the phase \"candidates\", what every rank does alike, is %.0f %% of the candidates work)"
          % (100 * cand_serial))
    print("| ranks | link | imbalance (gathering, final) | received per rank (MB) | communication (s) | T_N (s) "
          "| speed-up | efficiency |")
    print("|---|---|---|---|---|---|---|---|")
    tiles = math.ceil(t["width"] / 16) * math.ceil(t["height"] / 16)
    passes = [p for p in t["records_per_pass"] if p > 0]
    measured, scale = {}, {}
    for m in a.measured:
        d = load(m)
        measured[d["ranks"]] = max(r["comm_bytes"] for r in d["per_rank"])
        scale[d["ranks"]] = measured[d["ranks"]] / max(d["per_rank"][0]["comm_bytes"], 1)
    traced = None
    if a.trace:
        if len(a.measured) != 1:
            raise SystemExit("--trace needs the stats of the same run in one --measured")
        traced = read_trace(a.trace)
        traced["ranks"] = load(a.measured[0])["ranks"]
        print("\ntrace (rank 0, %d ranks): %d exchanges, %d rounds, %.1f MB in them; %.1f MB of finished tiles "
              "streamed (%.1f MB during the pilot)" % (traced["ranks"], traced["exchanges"], traced["rounds"],
                                                        traced["bytes"] / 1e6, traced["streamed"] / 1e6,
                                                        traced["streamed_pilot"] / 1e6))
    for n in sorted(set(a.ranks) | set(measured)):
        z = math.sqrt(2 * math.log(n)) if a.sqrt2ln else expected_max_normal(n)
        # Gathering: pass by pass, weighted by the pass's records.
        imb_g = sum(p * math.ceil(p / n) / (p / n) * (1 + a.record_cv * z / math.sqrt(math.ceil(p / n)))
                    for p in passes) / sum(passes)
        imb_f = math.ceil(tiles / n) / (tiles / n) * (1 + a.tile_cv * z / math.sqrt(math.ceil(tiles / n)))
        if not a.interleaved_final:
            # The pilot (a quarter of the samples) stays interleaved; the rest is shared out by cost, longest
            # tile first to the least loaded rank, whose excess is at most one tile (taken as 1 + 3 cv times
            # the mean tile) over a mean load of tiles / N tiles.
            imb_f = 0.25 * imb_f + 0.75 * (1 + (1 + 3 * a.tile_cv) / (tiles / n))
        share = (n - 1) / n
        film, streamed = px * 24 * a.tiles_moved, px * (8 + 12)
        if a.film_doubles or a.sum_image:
            film, streamed = px * (4 + 3) * 8 * (2 if a.sum_image else 1), 0
        volume = (records * record_bytes * share + other_bytes_2 * px_ratio * share / 0.5 + film * share +
                  (px * 1 + records * 88) * share)
        if n in measured:
            volume = measured[n] - streamed * share
        exchanges = a.collectives * t["passes"]
        rounds = (exchanges * (n - 1) if a.ring else
                  (exchanges - t["passes"] - LARGE_EXCHANGES) * math.ceil(math.log2(n)) +
                  (t["passes"] + LARGE_EXCHANGES) * (n - 1))
        for gbps in a.links:
            rate = gbps * 1e9 / 8
            latency = rounds * ALPHA[gbps]
            final = shared["final render"] / n * imb_f
            unhidden = (max(0.0, 8 * px * share / rate - 0.25 * final) + max(0.0, 12 * px * share / rate - 0.75 * final)
                        if streamed else 0.0)
            comm = volume / rate + latency + unhidden
            volume_shown = volume + streamed * share
            if traced and n == traced["ranks"]:
                # The trace's exchanges, scaled to the rank that received most; each pass's streamed tiles
                # are hidden behind that pass's rendering on this rank (the pilot a quarter of the final
                # render, the second pass the rest) except what does not fit, and the last tile's messages.
                k = scale[n]
                tile = (16 * 16 * 12 + 8) * (n - 1)
                hidden = (max(0.0, k * traced["streamed_pilot"] / rate - 0.25 * final) +
                          max(0.0, k * (traced["streamed"] - traced["streamed_pilot"]) / rate - 0.75 * final) +
                          2 * tile / rate)
                volume_shown = k * (traced["bytes"] + traced["streamed"])
                comm = k * traced["bytes"] / rate + traced["rounds"] * ALPHA[gbps] + hidden
            tn = (serial + (band if n > 1 else 0.0) + (shared["gathering"] + shared["candidates"] + shared["points, filter, validity"]) / n * imb_g
                  + shared["final render"] / n * imb_f + comm)
            print("| %d%s | %d Gb/s | %.2f, %.2f | %.1f | %.2f | %.1f | %.1f | %.2f |"
                  % (n, " (traced)" if traced and n == traced["ranks"] else " (bytes measured)" if n in measured else "", gbps, imb_g, imb_f, volume_shown / 1e6, comm, tn, total_1 / tn, total_1 / (n * tn)))
        if n == max(set(a.ranks) | set(measured)):
            ideal = serial + sum(shared.values()) / n
            print("\nwithout imbalance and communication, %d ranks: T_N = %.1f s, efficiency %.2f (Amdahl: %.1f s "
                  "done by every rank)" % (n, ideal, total_1 / (n * ideal), serial))


if __name__ == "__main__":
    main()
