#!/usr/bin/env bash
# The README's two commands as a new user meets them: a fresh clone of this repository's HEAD in
# a temporary folder, an empty HOME (no Dr.Jit kernel cache, no raycheck cache, no pip cache),
# none of this shell's RAYCHECK_/DRJIT_ settings and not CI's full matrix; then `make install`
# and `make report` (the README's first command: their sum is what a new user waits for it, and
# the report's own phases are printed) and `make test` (N times in a row), each one's status and
# time printed, its output in a log beside the clone (the folder is kept when a command failed, or with --keep). Run it
# before a release; the machine-wide parts the Makefile installs (libllvm19, chromium) stay
# installed, as they would on a user's machine after the first run.
#
#     bash tools/fresh_machine.sh [--test-runs N] [--no-report] [--keep] [--ci]
#
# Exit status: 0 when every command passed, 1 when any failed (or the clone did), 2 for bad
# usage, 130 when interrupted (SIGINT), 143 when terminated (SIGTERM): the running command's
# processes are stopped first.
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
work=$(mktemp -d "${TMPDIR:-/tmp}/raycheck-fresh-XXXXXX") || {
    echo "fresh_machine: cannot make a temporary folder" >&2
    exit 1
}
failed=0
child=""  # the running command's process group (its own session)
cleanup() {
    if [ "$keep" = 1 ] || [ "$failed" = 1 ]; then
        echo "kept: $work" >&2
    else
        rm -rf "$work"
    fi
}
stop() {  # stop WORD STATUS: the running command and what it started, then this script
    echo "fresh_machine: $1" >&2
    if [ -n "$child" ]; then
        kill -TERM -- "-$child" 2>/dev/null
        wait "$child" 2>/dev/null
    fi
    failed=1  # what ran so far stays for a look
    exit "$2"
}
trap cleanup EXIT
trap 'stop interrupted 130' INT
trap 'stop terminated 143' TERM

if [ -n "$(git -C "$repo" status --porcelain --untracked-files=no)" ]; then
    echo "note: $repo has uncommitted changes; the clone holds HEAD only" >&2
fi
git clone --quiet --no-hardlinks "$repo" "$work/raycheck" || { failed=1; exit 1; }
mkdir "$work/home"
echo "clone of $(git -C "$work/raycheck" log -1 --format='%h %s') in $work/raycheck"
echo "HOME=$work/home (empty); logs in $work"

# a new user's environment: this shell's raycheck, Dr.Jit, pytest and make settings, its
# virtual environment and CI's marker dropped
fresh_env=(env -u CI -u PIP_CACHE_DIR -u XDG_CACHE_HOME -u PYTEST_ADDOPTS -u VIRTUAL_ENV
           -u MAKEFLAGS -u MAKELEVEL -u MFLAGS HOME="$work/home")
for name in $(compgen -e); do
    case "$name" in RAYCHECK_* | DRJIT_*) fresh_env+=(-u "$name") ;; esac
done
[ "$ci" = 1 ] && fresh_env+=(CI=true)

results=()
run() {  # run LABEL LOG COMMAND...: one line with the status and the wall time
    local label=$1 log=$2
    shift 2
    local start end status
    start=$(date +%s.%N)
    # a session of its own, so that stop() can end it and everything it started
    (cd "$work/raycheck" && exec setsid "${fresh_env[@]}" "$@") >"$log" 2>&1 &
    child=$!
    wait "$child"
    status=$?
    child=""
    end=$(date +%s.%N)
    local line
    seconds=$(awk "BEGIN { print $end - $start }")
    line=$(printf '%-16s status %-3d %8.1f s   (log: %s)' "$label" "$status" "$seconds" "$log")
    echo "$line"
    results+=("$line")
    if [ "$status" -ne 0 ]; then
        failed=1
        tail -n 25 "$log" | sed 's/^/    | /'
    fi
    return "$status"
}

seconds=0  # the last command's wall time
if [ "$report" = 1 ]; then
    run "make install" "$work/make-install.log" make install
    installed=$seconds
    run "make report" "$work/make-report.log" make report
    # the report's phases (raycheck report prints them), its summary and where it is
    grep -E '^(phases:|[0-9]+ comparisons)' "$work/make-report.log" | sed 's/^/    /'
    line=$(printf '%-16s %19.1f s   (make install + make report: a new user'"'"'s wait)' \
        "fresh report" "$(awk "BEGIN { print $installed + $seconds }")")
    echo "$line"
    results+=("$line")
fi
for i in $(seq 1 "$test_runs"); do
    run "make test #$i" "$work/make-test-$i.log" make test
    # pytest's last line: how many passed, failed and skipped, and its own time
    grep -E '(passed|failed|error)' "$work/make-test-$i.log" | tail -n 1 | sed 's/^/    /'
done

echo
echo "summary ($(nproc) cores, $(date -u +%Y-%m-%dT%H:%MZ)):"
printf '  %s\n' "${results[@]}"
exit "$failed"
