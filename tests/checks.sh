# checks.sh - the counted checks of the shell tests (cli_test.sh,
# bench_smoke.sh, fault_test.sh); source it, do not run it.
#
#   check DESCRIPTION COMMAND...   one check: passes when COMMAND succeeds,
#                                  else prints "FAIL: DESCRIPTION"
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
