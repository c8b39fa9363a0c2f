#!/usr/bin/env bash
# Rewrites the option tables of README.md (between the options:begin and options:end markers) from
# the command's own table: `irrcache render --help-markdown`. Usage: bash scripts/update-readme-options.sh [BINARY]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-build/irrcache}
tables=$("$bin" render --help-markdown)
python3 - "$tables" <<'PY'
import re, sys
s = open("README.md").read()
begin = s.index("<!-- options:begin")
begin = s.index("\n", begin) + 1
end = s.index("<!-- options:end -->")
tmp = "README.md.tmp"
open(tmp, "w").write(s[:begin] + sys.argv[1] + "\n" + s[end:])
import os
os.replace(tmp, "README.md")
PY
echo "README.md: option tables rewritten"
