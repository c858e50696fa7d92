# checks.sh - the counted checks of the shell tests (cli_test.sh,
# visible_test.sh, bench_smoke.sh, fault_test.sh); source it, do not run it.
#
#   check DESCRIPTION COMMAND...   one check: passes when COMMAND succeeds,
#                                  else prints "FAIL: DESCRIPTION"
#   run COMMAND...                 runs it: stdout in $OUT, stderr in $ERR,
#                                  exit code in $status (the script sets OUT, ERR)
#   expect CODE DESCRIPTION COMMAND...  runs COMMAND, one check of its exit code
#   stdout_has RE, stderr_has TEXT, stderr_matches RE   for check's COMMAND
#
# It keeps the counts in $passed and $failed, which each script reports as
# its last line, "N passed, M failed", and turns into its exit status.

passed=0
failed=0

check() {
    local what=$1
    shift
    if "$@"; then
        passed=$((passed + 1))
    else
        failed=$((failed + 1))
        echo "FAIL: $what"
    fi
}

run() {
    "$@" >"$OUT" 2>"$ERR"
    status=$?
}

expect() {
    local code=$1 what=$2
    shift 2
    run "$@"
    if [ "$status" -eq "$code" ]; then
        passed=$((passed + 1))
    else
        failed=$((failed + 1))
        echo "FAIL: $what: exit $status, expected $code"
        sed 's/^/    stderr: /' "$ERR" | head -n 5
    fi
}

stdout_has() { grep -q -e "$1" "$OUT"; }
stderr_has() { grep -q -F -e "$1" "$ERR"; }
stderr_matches() { grep -q -e "$1" "$ERR"; }
