#!/bin/bash
# Wall times of the case matrix by executor (docs/parallel-and-grading.md, "Running in parallel"): a full check of
# `python -m raycheck.tracer` with -j 1, -j 2 and on a two-worker Dask cluster on 127.0.0.1
# (dask scheduler + dask worker, as docs/parallel-and-grading.md shows), `raycheck report` (make report) with
# -j 1 and -j 2, and grading 20 wrapper submissions (tests/wrappers/corrupt.py defects).
# Every row starts with an empty $RAYCHECK_CACHE of its own (OUT/cache/LABEL), so that no row
# reuses the reference renders and distributions of the rows before it; Dr.Jit's kernel cache
# (~/.drjit) is left as it is.
# Usage: bash tools/bench_parallel.sh [OUT]   (default /tmp/raycheck-bench; ~20 min on 2 cores)
set -u
OUT=${1:-/tmp/raycheck-bench}
BIN=$(pwd)/.venv/bin
PY=$BIN/python
rm -rf "$OUT/cache" "$OUT/times.txt"
mkdir -p "$OUT"
t() {  # t LABEL COMMAND...: one line "LABEL seconds"
    local start end rc
    start=$(date +%s.%N)
    RAYCHECK_CACHE="$OUT/cache/$1" "${@:2}" > "$OUT/$1.log" 2>&1
    rc=$?
    end=$(date +%s.%N)
    printf '%-28s %7.1f s (exit %s)\n' "$1" "$(echo "$end - $start" | bc)" "$rc" | tee -a "$OUT/times.txt"
}
CAND="$PY -m raycheck.tracer"
t check-j1 "$BIN/raycheck" check --renderer "$CAND" --out "$OUT/check-j1" --quiet -j 1
t check-j2 "$BIN/raycheck" check --renderer "$CAND" --out "$OUT/check-j2" --quiet -j 2
"$BIN/dask" scheduler --host 127.0.0.1 --port 8786 --no-dashboard > "$OUT/scheduler.log" 2>&1 &
SCHED=$!
RAYCHECK_CACHE="$OUT/cache/check-dask2" "$BIN/dask" worker tcp://127.0.0.1:8786 --nworkers 2 \
    --nthreads 1 --host 127.0.0.1 --no-dashboard > "$OUT/worker.log" 2>&1 &
WORKER=$!
sleep 8
t check-dask2 "$BIN/raycheck" check --renderer "$CAND" --out "$OUT/check-dask" --quiet \
    --scheduler tcp://127.0.0.1:8786
kill "$WORKER" "$SCHED"
wait "$WORKER" "$SCHED" 2>/dev/null
t report-j1 "$BIN/raycheck" report --out "$OUT/report-j1" --quiet -j 1
t report-j2 "$BIN/raycheck" report --out "$OUT/report-j2" --quiet -j 2
DEFECTS=(none no_shadows filter_2x flip no_normals exit3 sleep truncate double_size segv)
SUBS=()
for i in $(seq 1 20); do
    d=${DEFECTS[$(( (i - 1) % 10 ))]}
    mkdir -p "$OUT/class/s$i"
    printf '#!/bin/sh\nexec %s %s %s "$@"\n' "$PY" "$(pwd)/tests/wrappers/corrupt.py" "$d" \
        > "$OUT/class/s$i/a2"
    chmod +x "$OUT/class/s$i/a2"
    SUBS+=("$OUT/class/s$i")
done
t grade20-j2 "$BIN/raycheck" grade "${SUBS[@]}" --scenes course/arch features/shadows \
    --timeout 10 --out "$OUT/grade" --quiet -j 2
# the harness's own serial share: every case cached, only the pages and files written again
t check-resumed "$BIN/raycheck" check --renderer "$CAND" --out "$OUT/check-j1" --quiet -j 1 \
    --resume
