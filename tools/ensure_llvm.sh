#!/usr/bin/env bash
# Dr.Jit's CPU backend loads the system libLLVM at run time and needs LLVM >= 17; Debian 12's
# default LLVM 15 aborts the process on the first kernel. Make sure a usable one is present.
set -eu
for v in 21 20 19 18 17; do
  for d in /usr/lib/x86_64-linux-gnu /usr/lib/aarch64-linux-gnu /usr/lib/llvm-$v/lib /usr/lib; do
    if ls "$d"/libLLVM-$v.so* "$d"/libLLVM.so.$v* >/dev/null 2>&1; then
      echo "libLLVM $v found in $d"
      exit 0
    fi
  done
done
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  echo "No libLLVM >= 17 found; installing Debian's libllvm19"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19 >/dev/null
  exit 0
fi
echo "raycheck needs libLLVM 17 or newer for Dr.Jit's CPU backend, and none was found." >&2
echo "Install it with:  sudo apt-get install libllvm19" >&2
echo "or set DRJIT_LIBLLVM_PATH to a libLLVM.so of version 17 or newer." >&2
exit 1
