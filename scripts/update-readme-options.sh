#!/usr/bin/env bash
# Rewrites the option tables of README.md from the commands' own tables (cli/options.h): between the
# options:begin and options:end markers `irrcache render --help-markdown`, between points-options:begin
# and points-options:end `irrcache points --help-markdown`, between diff-options:begin and
# diff-options:end `irrcache diff --help-markdown`. Usage: bash scripts/update-readme-options.sh [BINARY]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-build/irrcache}
render=$("$bin" render --help-markdown)
points=$("$bin" points --help-markdown)
diff=$("$bin" diff --help-markdown)
python3 - "$render" "$points" "$diff" <<'PY'
import os, sys
s = open("README.md").read()
for marker, tables in zip(("options", "points-options", "diff-options"), sys.argv[1:]):
    begin = s.index("<!-- %s:begin" % marker)
    begin = s.index("\n", begin) + 1
    end = s.index("<!-- %s:end -->" % marker)
    s = s[:begin] + tables + "\n" + s[end:]
tmp = "README.md.tmp"
open(tmp, "w").write(s)
os.replace(tmp, "README.md")
PY
echo "README.md: option tables rewritten"
