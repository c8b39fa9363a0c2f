#!/usr/bin/env python3
"""Unit tests of bench/report (no rendering): the PNG decoder against every row filter, crops, the
equal-quality interpolation and extrapolation against an exact 1/spp curve, the BENCHMARKS.md marker
rewrite (text outside the markers untouched), the SVG plots, the consistency checks catching a bad run, and
bench/gather_oracle.py's reading of its measurement lines (and that its patch still applies to the tree).
Run: python3 tests/bench/test_bench_tools.py (CTest: bench_tools)."""

import os
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.dont_write_bytecode = True  # no __pycache__ folders in the source tree
sys.path.insert(0, os.path.join(ROOT, "bench"))

from report import analysis, check, plot, pngio  # noqa: E402
import accuracy_sweep  # noqa: E402
import gather_oracle  # noqa: E402


def encode_with_filters(width, height, channels, pixels, filters):
    """A PNG whose row y uses filter filters[y % len(filters)] (the decoder must undo all five)."""
    stride = width * channels
    prev = bytearray(stride)
    raw = bytearray()
    for y in range(height):
        line = pixels[y * stride:(y + 1) * stride]
        ft = filters[y % len(filters)]
        out = bytearray(stride)
        for i in range(stride):
            left = line[i - channels] if i >= channels else 0
            up = prev[i]
            ul = prev[i - channels] if i >= channels else 0
            pred = [0, left, up, (left + up) >> 1, pngio._paeth(left, up, ul)][ft]
            out[i] = (line[i] - pred) & 255
        raw += bytes([ft]) + out
        prev = bytearray(line)

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
    ctype = {1: 0, 3: 2, 4: 6}[channels]
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, ctype, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(bytes(raw))) + chunk(b"IEND", b""))


class PngTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="ic-bench-test-")

    def test_every_filter_decodes(self):
        w, h, c = 13, 10, 3
        pixels = bytes((x * 37 + y * 11 + k * 101 + (x * y) % 7) & 255 for y in range(h) for x in range(w)
                       for k in range(c))
        path = os.path.join(self.tmp, "f.png")
        with open(path, "wb") as f:
            f.write(encode_with_filters(w, h, c, pixels, [0, 1, 2, 3, 4]))
        img = pngio.read_png(path)
        self.assertEqual((img.width, img.height, img.channels), (w, h, c))
        self.assertEqual(img.pixels, pixels)

    def test_write_read_round_trip_and_crop(self):
        w, h = 20, 10
        pixels = bytes((x + 3 * y + k) & 255 for y in range(h) for x in range(w) for k in range(4))
        path = os.path.join(self.tmp, "rgba.png")
        pngio.write_png(path, pngio.Image(w, h, 4, pixels))
        img = pngio.read_png(path)
        self.assertEqual(img.pixels, pixels)
        c = pngio.crop_fraction(img, (0.5, 0.5, 1.0, 1.0))
        self.assertEqual((c.width, c.height), (10, 5))
        self.assertEqual(c.pixels[:4], pixels[(5 * w + 10) * 4:(5 * w + 10) * 4 + 4])

    def test_blank_image_has_no_variance(self):
        mean, var, distinct = pngio.luma_stats(pngio.Image(4, 4, 3, bytes([200, 200, 200]) * 16))
        self.assertEqual((round(mean), var, distinct), (200, 0.0, 1))

    def test_not_a_png(self):
        path = os.path.join(self.tmp, "x.png")
        with open(path, "wb") as f:
            f.write(b"GIF89a")
        with self.assertRaises(pngio.PngError):
            pngio.read_png(path)


def exact_curve(c=0.2, fixed=0.1, per_spp=0.01, spps=(1, 2, 4, 8, 16)):
    return [{"spp": s, "seconds": fixed + per_spp * s, "render_seconds": per_spp * s, "relmse": c / s} for s in spps]


class EqualQualityTest(unittest.TestCase):
    def test_measured_point_is_hit(self):
        r = analysis.equal_quality_time(exact_curve(), 0.2 / 4)
        self.assertEqual(r["method"], "interpolated")
        self.assertAlmostEqual(r["seconds"], 0.14, places=9)
        self.assertAlmostEqual(r["spp"], 4, places=9)

    def test_interpolation_is_between_neighbours(self):
        r = analysis.equal_quality_time(exact_curve(), 0.2 / 6)
        self.assertEqual(r["method"], "interpolated")
        self.assertTrue(0.14 < r["seconds"] < 0.18)
        self.assertAlmostEqual(r["spp"], 6, places=9)  # exact: the curve is a straight line in log-log

    def test_extrapolation_follows_one_over_spp(self):
        r = analysis.equal_quality_time(exact_curve(), 0.2 / 64)
        self.assertEqual(r["method"], "extrapolated")
        self.assertAlmostEqual(r["spp"], 64, places=9)
        self.assertAlmostEqual(r["seconds"], 0.1 + 0.01 * 64, places=9)

    def test_worse_than_one_sample(self):
        r = analysis.equal_quality_time(exact_curve(), 0.4)
        self.assertEqual(r["method"], "extrapolated (<1 spp)")
        self.assertAlmostEqual(r["spp"], 0.5, places=9)
        self.assertAlmostEqual(r["seconds"], 0.105, places=9)

    def test_reference_floor_is_flagged(self):
        self.assertTrue(analysis.equal_quality_time(exact_curve(), 0.0003, spp_ref=1024)["below_reference_floor"])
        self.assertFalse(analysis.equal_quality_time(exact_curve(), 0.01, spp_ref=1024)["below_reference_floor"])

    def test_extrapolation_uses_a_faster_fitted_order(self):
        # a curve converging as 1/spp^1.5: extrapolating with that order, not 1/spp
        curve = [dict(p, relmse=0.2 / p["spp"] ** 1.5) for p in exact_curve()]
        r = analysis.equal_quality_time(curve, 0.2 / 64 ** 1.5)
        self.assertAlmostEqual(r["order"], 1.5, places=9)
        self.assertAlmostEqual(r["spp"], 64, places=6)

    def test_order_is_never_below_one(self):
        # a curve flattening on a noise floor must not be extrapolated slower than 1/spp
        curve = [dict(p, relmse=0.2 / p["spp"] ** 0.5) for p in exact_curve()]
        r = analysis.equal_quality_time(curve, 0.2 / 4 ** 0.5 / 16)
        self.assertEqual(r["order"], 1.0)

    def test_reference_noise_is_subtracted(self):
        # every measured error carries the reference's noise n: with n given, the exact curve is recovered
        n = 0.001
        noisy = [dict(p, relmse=p["relmse"] + n) for p in exact_curve()]
        r = analysis.equal_quality_time(noisy, 0.2 / 64 + n, ref_noise=n)
        self.assertEqual(r["method"], "extrapolated")
        self.assertAlmostEqual(r["spp"], 64, places=6)
        self.assertFalse(r["lower_bound"])
        # without the correction the same numbers give a smaller speed-up
        self.assertLess(analysis.equal_quality_time(noisy, 0.2 / 64 + n)["spp"], 64)

    def test_unresolvable_error_gives_a_lower_bound(self):
        n = 0.001
        noisy = [dict(p, relmse=p["relmse"] + n) for p in exact_curve()]
        r = analysis.equal_quality_time(noisy, n * 1.1, ref_noise=n)
        self.assertTrue(r["lower_bound"])
        self.assertTrue(r["below_reference_floor"])
        self.assertAlmostEqual(r["spp"], 0.2 / (0.25 * n), places=3)

    def test_unusable_input(self):
        self.assertIsNone(analysis.equal_quality_time([], 0.1))
        self.assertIsNone(analysis.equal_quality_time(exact_curve(), float("nan")))
        self.assertIsNone(analysis.equal_quality_time(exact_curve(), 0))


class MarkerTest(unittest.TestCase):
    def test_replaces_only_between_markers(self):
        text = "# Benchmarks\n\nintro by someone else\n\n<!-- bench:begin -->\nold\n<!-- bench:end -->\n\n## Other\nkeep\n"
        new = analysis.replace_marked_section(text, "new table\n")
        self.assertEqual(new, text.replace("old", "new table"))
        self.assertEqual(analysis.replace_marked_section(new, "new table\n"), new)

    def test_appends_when_absent(self):
        new = analysis.replace_marked_section("# Benchmarks\n\nother text", "body")
        self.assertTrue(new.startswith("# Benchmarks\n\nother text\n\n<!-- bench:begin -->\nbody\n<!-- bench:end -->"))
        self.assertTrue(analysis.replace_marked_section("", "b").startswith("# Benchmarks\n"))

    def test_lone_marker_is_an_error(self):
        with self.assertRaises(ValueError):
            analysis.replace_marked_section("<!-- bench:begin -->\nx\n", "body")

    def test_file_update(self):
        path = os.path.join(tempfile.mkdtemp(prefix="ic-bench-test-"), "BENCHMARKS.md")
        with open(path, "w") as f:
            f.write("# B\n\nmine\n")
        analysis.update_marked_file(path, "table")
        analysis.update_marked_file(path, "table 2")
        with open(path) as f:
            self.assertEqual(f.read(), "# B\n\nmine\n\n<!-- bench:begin -->\ntable 2\n<!-- bench:end -->\n")


class PlotTest(unittest.TestCase):
    def test_series_are_drawn(self):
        svg = plot.loglog_svg([{"label": "pt", "points": [(0.1, 1), (1, 0.1)]},
                               {"label": "ic", "points": [(0.5, 0.05), (float("nan"), 1), (0, 2)]}], "s", "e", "t")
        self.assertEqual(svg.count('class="series"'), 2)
        self.assertIn("<svg", svg)

    def test_no_data(self):
        self.assertIn("no data", plot.loglog_svg([{"label": "x", "points": []}], "s", "e", "t"))


def fake_results(out_dir, pt_errors=(0.2, 0.1, 0.05), records=10):
    png = os.path.join(out_dir, "x.png")
    pngio.write_png(png, pngio.Image(2, 2, 3, bytes(12)))
    with open(os.path.join(out_dir, "report.html"), "w") as f:
        f.write('<svg class="plot"></svg><img src="x.png">')
    m = lambda e: {"rmse": e, "relmse": e, "psnr_hdr": 30.0, "psnr_ldr": 30.0, "ssim": 0.9, "nonfinite": 0}  # noqa
    curve = [{"label": "%d spp" % (1 << i), "spp": 1 << i, "metrics": m(e)} for i, e in enumerate(pt_errors)]
    cache = [{"tag": "lazy-default", "records": records, "seconds": 1.0, "metrics": m(0.04),
              "equal_quality": {"speedup": 1.5, "method": "extrapolated"},
              "equal_time": {"pt": {"metrics": m(0.05)}, "relmse_ratio": 1.25}}]
    return {"scenes": [{"name": "s", "reference": {"self_diff": {"rmse": 0, "relmse": 0}, "noise_relmse": 0.001}, "pt_curve": curve,
                        "cache": cache}]}


def load_bench_run():
    import importlib.machinery
    import importlib.util
    loader = importlib.machinery.SourceFileLoader("bench_run", os.path.join(ROOT, "bench", "run"))
    spec = importlib.util.spec_from_loader("bench_run", loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


class SceneFilesTest(unittest.TestCase):
    def test_dependencies_and_missing_meshes(self):
        run = load_bench_run()
        d = tempfile.mkdtemp(prefix="ic-bench-test-")
        os.makedirs(os.path.join(d, "tex"))
        files = {"box.obj": "mtllib box.mtl\nv 0 0 0\n", "box.mtl": "newmtl m\nmap_Kd tex\\wood.png\n",
                 "tex/wood.png": "x", "scene.json": '{"meshes": [{"path": "box.obj"}, {"path": "shared:nope/x.obj"}],'
                                                  ' "_about": "not a path"}'}
        for name, text in files.items():
            with open(os.path.join(d, name), "w") as f:
                f.write(text)
        found, missing = run.scene_files(os.path.join(d, "scene.json"), os.path.join(d, "no-such-dir"))
        self.assertEqual([os.path.relpath(p, d) for p in found], ["scene.json", "box.obj", "box.mtl", "tex/wood.png"])
        self.assertEqual(missing, ["shared:nope/x.obj"])
        key = run.reference_key(found, {"spp": 4})
        self.assertEqual(key, run.reference_key(found, {"spp": 4}))
        self.assertNotEqual(key, run.reference_key(found, {"spp": 8}))
        with open(os.path.join(d, "tex/wood.png"), "w") as f:
            f.write("y")
        self.assertNotEqual(key, run.reference_key(found, {"spp": 4}))


class CheckTest(unittest.TestCase):
    def setUp(self):
        self.out = tempfile.mkdtemp(prefix="ic-bench-test-")

    def test_consistent_run_passes(self):
        self.assertEqual(check.check_results(fake_results(self.out), self.out), [])

    def test_rising_pt_error_and_missing_records_fail(self):
        problems = check.check_results(fake_results(self.out, pt_errors=(0.2, 0.3, 0.05), records=0), self.out)
        self.assertTrue(any("does not fall" in p for p in problems), problems)
        self.assertTrue(any("records" in p for p in problems), problems)

    def test_noisy_reference_fails(self):
        r = fake_results(self.out)
        r["scenes"][0]["reference"]["noise_relmse"] = 1.0  # noisier than the path tracer's last point
        self.assertTrue(any("too few samples" in p for p in check.check_results(r, self.out)))
        r["scenes"][0]["reference"]["noise_relmse"] = float("nan")
        self.assertTrue(any("measured noise" in p for p in check.check_results(r, self.out)))

    def test_broken_link_fails(self):
        r = fake_results(self.out)
        with open(os.path.join(self.out, "report.html"), "a") as f:
            f.write('<img src="missing.png">')
        self.assertTrue(any("missing.png" in p for p in check.check_results(r, self.out)))


class AccuracySweepTest(unittest.TestCase):
    """bench/accuracy_sweep.py: records at equal error along a baseline's lower envelope."""

    def test_envelope_drops_dominated_points(self):
        # (records, error): 300 records with more error than 200 records is not on the envelope
        front = accuracy_sweep.envelope([(100, 4.0), (300, 3.0), (200, 2.0), (400, 1.0)])
        self.assertEqual(front, [(100, 4.0), (200, 2.0), (400, 1.0)])

    def test_power_law_is_interpolated_exactly(self):
        # error = 1e4 / records²: log-log linear, so any error between two points maps back exactly
        front = accuracy_sweep.envelope([(r, 1e4 / r ** 2) for r in (100, 200, 400, 800)])
        for records in (100, 150, 333, 800):
            self.assertAlmostEqual(accuracy_sweep.records_at(front, 1e4 / records ** 2), records, places=6)

    def test_no_extrapolation(self):
        front = accuracy_sweep.envelope([(100, 4.0), (400, 1.0)])
        self.assertIsNone(accuracy_sweep.records_at(front, 5.0))
        self.assertIsNone(accuracy_sweep.records_at(front, 0.5))
        self.assertIsNone(accuracy_sweep.records_at([], 1.0))
        self.assertEqual(accuracy_sweep.records_at([(100, 2.0)], 2.0), 100)

    def test_error_at_equal_records(self):
        # the other reading of the same envelope: the error reached with a given number of records, exact on a
        # power law, the inverse of records_at, and None outside the envelope's records
        front = accuracy_sweep.envelope([(r, 1e4 / r ** 2) for r in (100, 200, 400, 800)])
        for records in (100, 150, 333, 800):
            self.assertAlmostEqual(accuracy_sweep.error_at(front, records), 1e4 / records ** 2, places=9)
            self.assertAlmostEqual(accuracy_sweep.records_at(front, accuracy_sweep.error_at(front, records)),
                                   records, places=6)
        self.assertIsNone(accuracy_sweep.error_at(front, 99))
        self.assertIsNone(accuracy_sweep.error_at(front, 801))
        self.assertIsNone(accuracy_sweep.error_at([], 100))
        self.assertEqual(accuracy_sweep.error_at([(100, 2.0)], 100), 2.0)


def oracle_line(mean, strat, unstrat, neyman, alloc25, alloc100, classes, cells=800):
    """One ORACLE line as bench/gather_oracle.patch prints it."""
    head = "ORACLE %d %g %g %g %g |" % (cells, mean, strat, unstrat, neyman)
    return head + " %s | %s |" % (" ".join("%g" % v for v in alloc25), " ".join("%g" % v for v in alloc100)) + \
        " " + " ".join("%g" % v for v in classes)


class GatherOracleTest(unittest.TestCase):
    def test_summary_of_two_records(self):
        # Record 1 (mean 2) and record 2 (mean 1): relative variances 0.01 and 0.03, so the mean is 0.02.
        classes1 = [10, 4, 0.04, 30, 8, 0.0] + [0] * 18     # escaped 10 rays, read records 30
        classes2 = [0, 0, 0, 20, 1, 0.02] + [0] * 18
        lines = [
            oracle_line(2.0, 0.04, 0.08, 0.01, [0.04, 0.02, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04], [0.04] * 8,
                        classes1),
            "ORACLE 800 1 0.03 | truncated by another thread's line",
            oracle_line(1.0, 0.03, 0.06, 0.0075, [0.03, 0.015, 0.03, 0.03, 0.03, 0.03, 0.03, 0.03], [0.03] * 8,
                        classes2),
            oracle_line(1.0, 1.0, 1.0, 1.0, [1.0] * 8, [1.0] * 8, classes2, cells=50),  # a hit record's grid
        ]
        rows = gather_oracle.parse(lines, 800)
        self.assertEqual(len(rows), 2)
        r = gather_oracle.summarize(rows)
        self.assertAlmostEqual(r["strat"], 0.02)
        self.assertAlmostEqual(r["unstrat"], 0.04)
        self.assertAlmostEqual(r["neyman"], 0.005)
        self.assertAlmostEqual(r["gains"][0][0], 2.0)   # the oracle sigma halves both records' variance
        self.assertAlmostEqual(r["gains"][0][1], 1.0)
        names = [c[0] for c in r["classes"]]
        self.assertEqual(names, ["escaped", "read records"])
        rays, light, var = r["classes"][0][1]
        self.assertAlmostEqual(rays, 10 / 60)
        self.assertAlmostEqual(light, (4 / 2) / (4 / 2 + 8 / 2 + 1))
        self.assertAlmostEqual(var, (0.04 / 4) / (0.04 / 4 + 0.02 / 1))  # each over its record's mean squared

    def test_patch_applies(self):
        git = shutil.which("git")
        if not git or not os.path.isdir(os.path.join(ROOT, ".git")):
            self.skipTest("not a git checkout")
        p = subprocess.run([git, "apply", "--check", os.path.join(ROOT, "bench", "gather_oracle.patch")], cwd=ROOT,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.assertEqual(p.returncode, 0, "bench/gather_oracle.patch no longer applies: " + p.stdout)


if __name__ == "__main__":
    unittest.main(verbosity=1)
