#!/usr/bin/env bash
# make-man.sh IRRCACHE_BINARY OUT.1 — the manual page irrcache(1), made from the command's own --help
# texts (the overview and each sub-command's), so that it always says what the installed binary does.
# Called by the build (cmake/install.cmake); `man -l OUT.1` shows it.
set -euo pipefail
bin=${1:?usage: make-man.sh IRRCACHE_BINARY OUT.1}
out=${2:?usage: make-man.sh IRRCACHE_BINARY OUT.1}
version=$("$bin" --version | head -n1)
# troff: a backslash is written \e, a line starting with . or ' is protected by \&.
escape() { sed -e 's/\\/\\e/g' -e "s/^\([.']\)/\\\\\&\1/"; }
tmp=$(mktemp "$out.tmp.XXXXXX")
trap 'rm -f "$tmp"' EXIT
{
  echo ".TH IRRCACHE 1 \"\" \"$version\" \"User Commands\""
  echo ".SH NAME"
  echo "irrcache \\- irradiance and radiance caching renderer"
  echo ".SH SYNOPSIS"
  echo ".nf"
  "$bin" --help | escape
  echo ".fi"
  for cmd in render diff points; do
    echo ".SH $(echo "$cmd" | tr a-z A-Z)"
    echo ".nf"
    "$bin" "$cmd" --help | escape
    echo ".fi"
  done
  echo ".SH SEE ALSO"
  echo "The documentation installed with irrcache (share/doc/irrcache): README.md and docs/."
} > "$tmp"
chmod 644 "$tmp"
mv "$tmp" "$out"
trap - EXIT
