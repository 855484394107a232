#!/usr/bin/env bash
# The README's two commands as a new user meets them: a fresh clone of this repository's HEAD in
# a temporary folder, an empty HOME (no Dr.Jit kernel cache, no raycheck cache, no pip cache),
# none of this shell's RAYCHECK_/DRJIT_ settings and not CI's full matrix; then `make test`
# (N times in a row) and `make report`, each one's status and time printed, its output kept in
# a log beside the clone. Run it before a release; the machine-wide parts the Makefile installs
# (libllvm19, chromium) stay installed, as they would on a user's machine after the first run.
#
#     bash tools/fresh_machine.sh [--test-runs N] [--no-report] [--keep] [--ci]
#
# Exit status: 0 when every command passed, 1 when any failed, 2 for bad usage, 130 when
# interrupted.
set -uo pipefail

usage() {
    echo "usage: bash tools/fresh_machine.sh [--test-runs N] [--no-report] [--keep] [--ci]" >&2
    exit 2
}

test_runs=1
report=1
keep=0
ci=0
while [ $# -gt 0 ]; do
    case "$1" in
        --test-runs)
            [ $# -ge 2 ] && [[ "$2" =~ ^[1-9][0-9]*$ ]] || usage
            test_runs=$2; shift 2 ;;
        --no-report) report=0; shift ;;
        --keep) keep=1; shift ;;
        --ci) ci=1; shift ;;
        *) usage ;;
    esac
done

repo=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/raycheck-fresh-XXXXXX")
cleanup() {
    if [ "$keep" = 1 ]; then
        echo "kept: $work" >&2
    else
        rm -rf "$work"
    fi
}
trap cleanup EXIT
trap 'echo "fresh_machine: interrupted" >&2; exit 130' INT
trap 'echo "fresh_machine: terminated" >&2; exit 143' TERM

if [ -n "$(git -C "$repo" status --porcelain --untracked-files=no)" ]; then
    echo "note: $repo has uncommitted changes; the clone holds HEAD only" >&2
fi
git clone --quiet --no-hardlinks "$repo" "$work/raycheck" || exit 2
mkdir "$work/home"
echo "clone of $(git -C "$work/raycheck" log -1 --format='%h %s') in $work/raycheck"
echo "HOME=$work/home (empty); logs in $work"

# a new user's environment: this shell's raycheck and Dr.Jit settings and CI's marker dropped
fresh_env=(env -u CI -u DRJIT_CACHE_DIR -u PIP_CACHE_DIR -u XDG_CACHE_HOME
           HOME="$work/home")
for name in $(env | sed -n 's/^\(RAYCHECK_[A-Za-z0-9_]*\)=.*/\1/p'); do
    fresh_env+=(-u "$name")
done
[ "$ci" = 1 ] && fresh_env+=(CI=true)

failed=0
results=()
run() {  # run LABEL LOG COMMAND...: one line with the status and the wall time
    local label=$1 log=$2
    shift 2
    local start end status
    start=$(date +%s.%N)
    (cd "$work/raycheck" && "${fresh_env[@]}" "$@") >"$log" 2>&1
    status=$?
    end=$(date +%s.%N)
    local line
    line=$(printf '%-16s status %-3d %8.1f s   (log: %s)' "$label" "$status" \
        "$(awk "BEGIN { print $end - $start }")" "$log")
    echo "$line"
    results+=("$line")
    if [ "$status" -ne 0 ]; then
        failed=1
        tail -n 25 "$log" | sed 's/^/    | /'
    fi
    return "$status"
}

for i in $(seq 1 "$test_runs"); do
    run "make test #$i" "$work/make-test-$i.log" make test
    # pytest's last line: how many passed, failed and skipped, and its own time
    grep -E '(passed|failed|error)' "$work/make-test-$i.log" | tail -n 1 | sed 's/^/    /'
done
if [ "$report" = 1 ]; then
    run "make report" "$work/make-report.log" make report
    tail -n 3 "$work/make-report.log" | sed 's/^/    /'
fi

echo
echo "summary ($(nproc) cores, $(date -u +%Y-%m-%dT%H:%MZ)):"
printf '  %s\n' "${results[@]}"
exit "$failed"
