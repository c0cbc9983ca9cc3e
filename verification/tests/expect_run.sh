#!/bin/sh
# Runs a command once and checks both its exit code and that its output (stdout and stderr) holds
# a fixed string. Usage: expect_run.sh CODE TEXT COMMAND [ARG...]; an argument @EMPTY@ is passed as
# an empty string (ctest cannot carry one).
# Prints the output, then what was missed, if anything; exits 0 when both hold, 1 otherwise.
code=$1
text=$2
shift 2
n=$#
i=0
while [ $i -lt $n ]; do
  a=$1
  shift
  [ "$a" = "@EMPTY@" ] && a=""
  set -- "$@" "$a"
  i=$((i + 1))
done
out=$("$@" 2>&1)
status=$?
printf '%s\n' "$out"
if [ "$status" -ne "$code" ]; then
  echo "expect_run: exit code $status, expected $code"
  exit 1
fi
if ! printf '%s\n' "$out" | grep -F -q -- "$text"; then
  echo "expect_run: the output does not contain '$text'"
  exit 1
fi
exit 0
