#!/usr/bin/env python3
"""What a record's hemisphere noise is made of, and how much any allocation of its rays could remove.

Needs a build with the measurement patch (it prints from inside the library, so it never ships):

    git apply bench/gather_oracle.patch
    cmake -S . -B build-oracle -DCMAKE_BUILD_TYPE=Release && cmake --build build-oracle -j2 --target irrcache_cli
    git apply -R bench/gather_oracle.patch
    python3 bench/gather_oracle.py scenes/staircase2.json --irrcache build-oracle/irrcache --width 320 --height 180 \
        [-- more irrcache render options]

Every K-th record's stratified gather (--every) is repeated 16 times with fresh jitter in each cell, which
gives each cell's ray mean mu_k and variance sigma_k^2. The script prints, over those records (each weighed
by its own mean squared, so that every record counts by its relative noise):

- the variance of the record's estimate: stratified (one ray a cell, as rendered), unstratified, and with
  the same rays allocated to the cells by Neyman's rule (n_k proportional to sigma_k; an oracle);
- with 25 % or 100 % more rays: uniform extra rays, against extra rays allocated by the oracle sigma
  (water-filling), by the oracle mu per cell and per 2x2 and 4x8 cells (a perfect guide: what a radiance
  field or the neighbours' records could give at best), by the record's own first rays per 2x2 and 4x8
  cells (leave-one-out, unbiased) and by its neighbours' spread (adaptive super-sampling);
- by ray class (escaped, read records, path-traced from an uncovered diffuse hit, path-traced from a glossy
  or specular hit; each also with a cached emitter hit): its share of the rays, of the light and of the
  within-cell variance (the noise the record carries). "Path-traced" is the class of the first hit: since
  the paths from such hits read the records at a later vertex (ic_path_start.cached), those two classes
  hold what is left of the continuation's noise, not all of a path's.

The repeated gathers read the same cache, so the noise of the records they read (hit records) is not part
of these variances: it is shared by every record that reads them.
"""
import argparse
import os
import subprocess
import sys
import tempfile

CLASSES = ["escaped", "read records", "uncovered diffuse hit, path-traced", "glossy or specular hit, path-traced"]
SCHEMES = ["uniform", "oracle sigma", "oracle mu", "oracle mu 2x2", "oracle mu 4x8", "own rays 2x2",
           "own rays 4x8", "neighbours' spread"]


def parse(lines, cells):
    rows = []
    for line in lines:
        if not line.startswith("ORACLE "):
            continue
        parts = line.split("|")
        head = parts[0].split()
        if len(parts) != 4 or len(head) != 6 or int(head[1]) != cells:
            continue
        try:
            mean = float(head[2])
            base = [float(x) for x in head[3:]]
            alloc = [[float(x) for x in parts[k].split()] for k in (1, 2)]
            cls = [float(x) for x in parts[3].split()]
        except ValueError:
            continue
        if mean > 0 and len(alloc[0]) == 8 and len(alloc[1]) == 8 and len(cls) == 24:
            rows.append((mean, base, alloc, cls))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--irrcache", default="build-oracle/irrcache")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=180)
    ap.add_argument("--every", type=int, default=25, help="measure every K-th record [25]")
    ap.add_argument("--cells", type=int, default=800, help="the image records' grid (M x N) [800]")
    ap.add_argument("--log", help="parse this stderr log instead of rendering")
    ap.epilog = "more irrcache render options go after --"
    argv = sys.argv[1:]
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    a = ap.parse_args(argv[:argv.index("--")] if "--" in argv else argv)
    a.options = extra
    if not a.log and not os.access(a.irrcache, os.X_OK):
        sys.exit("gather_oracle: %s is not an executable; build one with bench/gather_oracle.patch applied "
                 "(see the top of this file) or pass --irrcache" % a.irrcache)
    if a.log:
        lines = open(a.log).read().splitlines()
    else:
        with tempfile.TemporaryDirectory() as d:
            env = dict(os.environ, IC_ORACLE=str(a.every))
            cmd = [a.irrcache, "render", a.scene, "--integrator", "ic", "--width", str(a.width), "--height",
                   str(a.height), "-q", "-o", os.path.join(d, "o.pfm")] + a.options
            p = subprocess.run(cmd, env=env, stderr=subprocess.PIPE, text=True)
            if p.returncode != 0:
                sys.exit("gather_oracle: %s failed: %s" % (" ".join(cmd), p.stderr.strip()[-500:]))
            lines = p.stderr.splitlines()
    rows = parse(lines, a.cells)
    if not rows:
        sys.exit("gather_oracle: no ORACLE lines (is %s built with bench/gather_oracle.patch?)" % a.irrcache)
    r = summarize(rows)
    print("%s: %d records measured (16 repeats each)" % (a.scene, len(rows)))
    print("relative variance of a record: stratified %.3g (sigma/E %.1f %%), unstratified %.3g (%.2fx), "
          "Neyman allocation of the same rays %.3g (%.2fx less)"
          % (r["strat"], 100 * r["strat"] ** 0.5, r["unstrat"], r["unstrat"] / r["strat"], r["neyman"],
             r["strat"] / r["neyman"]))
    print("\nmore rays, allocated by ...: variance of uniform extra rays over each scheme's (> 1: better)")
    print("| extra rays | " + " | ".join(SCHEMES[1:]) + " |")
    print("|---" * len(SCHEMES) + "|")
    for label, gains in zip(["+25 %", "+100 %"], r["gains"]):
        print("| %s | " % label + " | ".join("%.2f" % g for g in gains) + " |")
    print("\n| ray class | rays | light | within-cell variance |")
    print("|---|---|---|---|")
    for name, shares in r["classes"]:
        print("| %s | %.1f %% | %.1f %% | %.1f %% |" % ((name,) + tuple(100 * x for x in shares)))


def summarize(rows):
    """Means over the records of the relative variances (each over its record's mean squared): strat,
    unstrat, neyman; gains[f][k]: uniform extra rays' variance over scheme k + 1's (f: +25 %, +100 %);
    classes: (name, (share of rays, of light, of within-cell variance)) for each class with rays."""
    def rel(get):
        return sum(get(r) / r[0] ** 2 for r in rows) / len(rows)
    out = {"strat": rel(lambda r: r[1][0]), "unstrat": rel(lambda r: r[1][1]), "neyman": rel(lambda r: r[1][2])}
    out["gains"] = []
    for f in range(2):
        u = rel(lambda r: r[2][f][0])
        out["gains"].append([u / rel(lambda r, k=k: r[2][f][k]) for k in range(1, 8)])
    # Rays count as they are, light over the record's mean, variance over its mean squared.
    sums = [[sum(r[3][3 * t + q] / r[0] ** q for r in rows) for q in range(3)] for t in range(8)]
    tot = [sum(sums[t][q] for t in range(8)) for q in range(3)]
    out["classes"] = [(CLASSES[t % 4] + (", a cached emitter" if t >= 4 else ""),
                       tuple(sums[t][q] / tot[q] if tot[q] > 0 else 0.0 for q in range(3)))
                      for t in range(8) if sums[t][0] > 0]
    return out

if __name__ == "__main__":
    main()
