#!/usr/bin/env bash
# The whole suite: once serially, then under mpirun with N ranks (default 2).
# Runs inside the image; `make test` calls it.
#
# It ends red, never hangs: each pass runs under a time limit
# (HFCDEM_PASS_LIMIT seconds, default 1800), a test that fails on one rank
# aborts every rank (tests/conftest.py), and a pass that did not finish counts
# as failed in the closing line.
set -uo pipefail
ranks=${1:-2}
limit=${HFCDEM_PASS_LIMIT:-1800}
cd "$(dirname "$0")/.."
export PYTHONPATH=$PWD${PYTHONPATH:+:$PYTHONPATH}
export logdir=${XDG_CACHE_HOME:-/tmp}/hfcdem-test-logs
mkdir -p "$logdir"
rm -f "$logdir"/*.xml "$logdir"/rank*.log

# run_pass NAME CMD...: the pass's exit code; 124 when the limit ended it
run_pass() {
    local name=$1; shift
    timeout --kill-after=30 "$limit" "$@"
    local rc=$?
    if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then
        echo "== $name pass: stopped after the ${limit} s limit (HFCDEM_PASS_LIMIT)"
        rc=124
    fi
    return $rc
}

t0=$SECONDS
echo "== serial: python3 -m pytest"
run_pass serial python3 -m pytest -q tests --junitxml="$logdir/serial.xml"
serial=$?
echo "== serial suite: exit $serial in $((SECONDS - t0)) s"

t1=$SECONDS
echo "== parallel: mpirun -n $ranks python3 -m pytest (rank 0 shown, others in $logdir)"
# every rank runs the same tests; only rank 0 prints, the others log to files
run_pass parallel mpirun -n "$ranks" bash -c '
  r=${OMPI_COMM_WORLD_RANK:-${PMIX_RANK:-0}}
  if [ "$r" = 0 ]; then exec python3 -m pytest -q --color=no tests --junitxml="$logdir/mpi.xml"
  else exec python3 -m pytest -q --color=no tests >"$logdir/rank$r.log" 2>&1; fi'
parallel=$?
if [ $parallel -ne 0 ]; then
  for f in "$logdir"/rank*.log; do [ -f "$f" ] && { echo "---- $f"; tail -60 "$f"; }; done
fi
echo "== parallel suite: exit $parallel in $((SECONDS - t1)) s"

# one closing line over both passes (rank 0's view of the parallel one); a pass
# that exited non-zero without a report (timeout, abort, crash) counts as failed
python3 - "$serial" "$logdir/serial.xml" "$parallel" "$logdir/mpi.xml" <<'PY'
import sys
import xml.etree.ElementTree as ET

n = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
unfinished = []
for name, rc, path in (("serial", sys.argv[1], sys.argv[2]), ("parallel", sys.argv[3], sys.argv[4])):
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        root = None
    if root is None or int(rc) in (124, 134, 137):
        why = "time limit" if int(rc) == 124 else f"exit {rc}, no report" if root is None else f"exit {rc}"
        unfinished.append(f"{name} ({why})")
        continue
    before = n["failures"] + n["errors"]
    for suite in root.iter("testsuite"):
        for key in n:
            n[key] += int(suite.get(key, 0))
    if int(rc) not in (0,) and n["failures"] + n["errors"] == before:
        unfinished.append(f"{name} (exit {rc} with no failed test: e.g. nothing collected)")
failed = n["failures"] + n["errors"]
passed = n["tests"] - failed - n["skipped"]
line = f"suite: {passed} passed, {failed} failed, {n['skipped']} skipped"
if unfinished:
    line += f"; {len(unfinished)} pass(es) did not finish, counted as failed: " + ", ".join(unfinished)
print(line)
PY

# pytest exits 5 when it collected nothing: that is a failure here too
[ $serial -eq 0 ] && [ $parallel -eq 0 ]
