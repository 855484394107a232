#!/usr/bin/env bash
# `raycheck grade` builds C++ submissions (cmake, g++) and runs every build and candidate in a
# bubblewrap sandbox (bwrap; setpriv from util-linux when the grader is root); a program that
# crashes runs again under gdb and valgrind for where (diagnosis/crash_site.py). Install
# Debian's packages where they are missing; elsewhere say what is missing (grading then falls
# back to rlimits with a warning, and the tests that need them are skipped).
set -eu
missing=()
command -v bwrap >/dev/null 2>&1 || missing+=(bubblewrap)
command -v cmake >/dev/null 2>&1 || missing+=(cmake)
command -v g++ >/dev/null 2>&1 || missing+=(g++)
command -v make >/dev/null 2>&1 || missing+=(make)
command -v gdb >/dev/null 2>&1 || missing+=(gdb)
command -v valgrind >/dev/null 2>&1 || missing+=(valgrind)
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  echo "Installing Debian's ${missing[*]} for grading from sources in a sandbox"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
  exit 0
fi
echo "Not found: ${missing[*]}: grading from sources, or in a sandbox, will not work." >&2
echo "Install them with:  sudo apt-get install ${missing[*]}" >&2
