#!/usr/bin/env python3
"""Opens the quick benchmark report (bench/run --quick) in headless Chromium and checks that it renders.

Checks: the page's own self-check (bench/report/report.js: every image decoded, every plot drawn, hovering
a record shows its tooltip, no script/resource error) passes, read from Chromium's DOM dump; Chromium logged
no console message from the page; a screenshot is not blank (decoded, its luma varies).

Chromium: $CHROMIUM, else chromium / chromium-browser / google-chrome on PATH; when none is found and we
run as root with apt-get, Debian's chromium package is installed. If that is impossible the test is skipped
with exit code 77 (CTest SKIP_RETURN_CODE).

usage: run_browser_test.py --report DIR [--irrcache PATH] [--work DIR]
  DIR holds report.html (the bench_quick test writes it); with --irrcache, a missing report is made first.
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.dont_write_bytecode = True  # no __pycache__ folders in the source tree
sys.path.insert(0, os.path.join(ROOT, "bench"))

from report import pngio  # noqa: E402

SKIP = 77


def say(msg):
    print("browser_report: " + msg, flush=True)


def find_chromium():
    env = os.environ.get("CHROMIUM")
    if env:
        return env if os.path.isfile(env) or shutil.which(env) else None
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        p = shutil.which(name)
        if p:
            return p
    return None


def install_chromium():
    if os.geteuid() != 0 or not shutil.which("apt-get"):
        say("SKIP: Chromium is not installed and cannot be installed here (needs root and apt-get); "
            "install it with: apt-get install -y chromium (or set $CHROMIUM)")
        return None
    say("Chromium not found; installing Debian's chromium package (apt-get)")
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    for cmd in (["apt-get", "update", "-qq"], ["apt-get", "install", "-y", "-qq", "chromium"]):
        try:
            p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900)
        except (OSError, subprocess.TimeoutExpired) as e:
            say("SKIP: %s failed: %s" % (" ".join(cmd), e))
            return None
        if p.returncode != 0:
            say("SKIP: %s failed (exit %d): %s" % (" ".join(cmd), p.returncode, p.stderr.strip()[-500:]))
            return None
    return find_chromium()


def chromium_cmd(chromium, profile, extra, url):
    return [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-quic",
            "--disable-extensions", "--disable-default-apps", "--mute-audio", "--hide-scrollbars",
            "--user-data-dir=" + profile, "--enable-logging=stderr", "--v=0",
            "--virtual-time-budget=15000"] + extra + [url]


def page_console_lines(stderr, url):
    """Console messages the page logged (Chromium prints them as ...:CONSOLE(line)] "text", source: url)."""
    return [line for line in stderr.splitlines() if "CONSOLE" in line and ("report" in line or url in line)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--report", required=True, help="folder with report.html")
    ap.add_argument("--irrcache", help="irrcache binary, to make the report when it is missing")
    ap.add_argument("--work", help="where to put the screenshot and DOM dump [a temporary folder]")
    opt = ap.parse_args()

    report = os.path.abspath(os.path.join(opt.report, "report.html"))
    if not os.path.isfile(report):
        if not opt.irrcache:
            say("FAIL: %s does not exist; run bench/run --quick --out %s first (the bench_quick test does)"
                % (report, opt.report))
            return 1
        say("no report yet; running bench/run --quick")
        p = subprocess.run([sys.executable, os.path.join(ROOT, "bench", "run"), "--quick", "--out", opt.report,
                            "--irrcache", opt.irrcache])
        if p.returncode != 0 or not os.path.isfile(report):
            say("FAIL: bench/run --quick failed (exit %d)" % p.returncode)
            return 1

    chromium = find_chromium() or install_chromium()
    if not chromium:
        return SKIP
    try:
        version = subprocess.run([chromium, "--version"], capture_output=True, text=True, timeout=60).stdout.strip()
    except (OSError, subprocess.TimeoutExpired) as e:
        say("SKIP: %s does not run: %s" % (chromium, e))
        return SKIP
    say("using %s (%s)" % (chromium, version))

    work = opt.work or tempfile.mkdtemp(prefix="ic-browser-")
    os.makedirs(work, exist_ok=True)
    url = "file://" + report
    failures = []

    # 1. the DOM after load: the page's self-check verdict
    profile = tempfile.mkdtemp(prefix="ic-chromium-profile-")
    try:
        p = subprocess.run(chromium_cmd(chromium, profile, ["--dump-dom"], url), capture_output=True, text=True,
                           timeout=180)
    except subprocess.TimeoutExpired:
        say("FAIL: chromium --dump-dom did not finish in 180 s")
        return 1
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    with open(os.path.join(work, "dom.html"), "w") as f:
        f.write(p.stdout)
    with open(os.path.join(work, "chromium-dom.log"), "w") as f:
        f.write(p.stderr)
    m = re.search(r'<pre id="selftest" data-status="([a-z]+)">(.*?)</pre>', p.stdout, re.S)
    if p.returncode != 0:
        failures.append("chromium --dump-dom exited %d: %s" % (p.returncode, p.stderr.strip()[-800:]))
    elif not m:
        failures.append("the DOM dump has no self-check element (page did not load?); see %s/dom.html" % work)
    else:
        say("page self-check: %s" % m.group(2).strip())
        if m.group(1) != "pass":
            failures.append("the page's self-check did not pass: %s" % m.group(2).strip())
    console = page_console_lines(p.stderr, url)
    if console:
        failures.append("the page logged console messages:\n  " + "\n  ".join(console[:20]))

    # 2. a screenshot: something is drawn
    shot = os.path.join(work, "screenshot.png")
    if os.path.exists(shot):
        os.remove(shot)
    profile = tempfile.mkdtemp(prefix="ic-chromium-profile-")
    try:
        p = subprocess.run(chromium_cmd(chromium, profile, ["--screenshot=" + shot, "--window-size=1400,2400"], url),
                           capture_output=True, text=True, timeout=180)
    except subprocess.TimeoutExpired:
        p = None
        failures.append("chromium --screenshot did not finish in 180 s")
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    if p is not None:
        with open(os.path.join(work, "chromium-screenshot.log"), "w") as f:
            f.write(p.stderr)
        if not os.path.isfile(shot):
            failures.append("chromium wrote no screenshot (exit %d): %s" % (p.returncode, p.stderr.strip()[-800:]))
        else:
            img = pngio.read_png(shot)
            mean, var, distinct = pngio.luma_stats(img, step=7)
            say("screenshot %dx%d: luma mean %.1f, variance %.1f, %d distinct values (%s)"
                % (img.width, img.height, mean, var, distinct, shot))
            if img.width < 200 or img.height < 200:
                failures.append("screenshot is only %dx%d" % (img.width, img.height))
            if var < 100 or distinct < 32:
                failures.append("screenshot looks blank (luma variance %.1f, %d distinct values)" % (var, distinct))

    if failures:
        for f_ in failures:
            say("FAIL: " + f_)
        return 1
    say("PASS: report renders in Chromium (outputs in %s)" % work)
    return 0


if __name__ == "__main__":
    sys.exit(main())
