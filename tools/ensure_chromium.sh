#!/usr/bin/env bash
# The report tests load the HTML pages in a real headless Chromium (Debian's package).
set -eu
if command -v chromium >/dev/null 2>&1; then
  exit 0
fi
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  echo "Installing Debian's chromium for the report's browser tests"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
  exit 0
fi
echo "No chromium found: the browser tests of the report will be skipped." >&2
echo "Install it with:  sudo apt-get install chromium" >&2
