#!/usr/bin/env bash
# Runs one hostile-input case (tests/hostile/README.md): CASE FMPC WORK_DIR [MEMORY_FACTOR].
# A case file is `key: value` lines, then a line `---`, then the input file's text (written to $INPUT):
#   args: check $INPUT           the fmpc command line, words as in bash; $INPUT, $DIR expand
#   exit: 2                      expected exit status
#   stderr: text                 a substring stderr must hold (repeatable); `stdout:` the same for stdout
#   input: rules.fis             the input's file name (default: the case's name + its .case-less extension)
#   generate: shell command      run in $DIR after the text is written: makes further inputs, or replaces $INPUT
#   max-seconds: 20              wall-clock limit (a hang or runaway is a failure)
#   max-rss-mib: 1024            peak resident memory (times MEMORY_FACTOR in sanitizer builds)
#   files: a.fzt b.h             the files the run may leave in $DIR besides its inputs (default: none)
#   unchanged: a.fis b.fis       inputs whose contents the run must leave as they were
#   address-space-mib: 2048      run under `ulimit -v` (a process memory limit); skipped, with exit status 77, in
#                                sanitizer builds, whose shadow memory needs more address space than any such limit
#   sanitizers: skip             not a test of the sanitizer build (hostile_cases.cmake): for cases that guard how the
#                                work grows with a large valid input, which the sanitizers slow 5 to 10 times
#                                and cannot make more right
# Every run checks, besides the exit status and messages, that nothing was written outside $DIR, that $DIR holds
# only the inputs and `files`, and that stderr stays under 64 KiB (diagnostics cap their count and excerpts).
set -uo pipefail
case_file=$1 fmpc=$2 work=$3 memory_factor=${4:-1}
name=$(basename "$case_file" .case)
fail() { echo "hostile case $name: FAILED: $*" >&2; exit 1; }

args="" exit_expected="" input_name="" generate="" max_seconds=20 max_rss=1024 files="" unchanged="" address_space=""
stderr_needles=() stdout_needles=()
body_start=0 line_no=0
while IFS= read -r line || [ -n "$line" ]; do
  line_no=$((line_no + 1))
  if [ "$line" = "---" ]; then body_start=$line_no; break; fi
  case "$line" in
    "#"*|"") ;;
    args:*) args=${line#args: } ;;
    exit:*) exit_expected=${line#exit: } ;;
    stderr:*) stderr_needles+=("${line#stderr: }") ;;
    stdout:*) stdout_needles+=("${line#stdout: }") ;;
    input:*) input_name=${line#input: } ;;
    generate:*) generate=${line#generate: } ;;
    max-seconds:*) max_seconds=${line#max-seconds: } ;;
    max-rss-mib:*) max_rss=${line#max-rss-mib: } ;;
    files:*) files=${line#files: } ;;
    unchanged:*) unchanged=${line#unchanged: } ;;
    address-space-mib:*) address_space=${line#address-space-mib: } ;;
    "sanitizers: skip") ;;
    *) fail "unknown line '$line' in $case_file" ;;
  esac
done < "$case_file"
[ -n "$args" ] && [ -n "$exit_expected" ] || fail "$case_file needs args: and exit:"
[ -n "$input_name" ] || input_name=$name.txt

rm -rf "$work"
mkdir -p "$work/dir"
DIR=$(cd "$work/dir" && pwd)
INPUT=$DIR/$input_name
export DIR INPUT
if [ "$body_start" -gt 0 ]; then
  tail -n +"$((body_start + 1))" "$case_file" > "$INPUT"
fi
if [ -n "$generate" ]; then
  (cd "$DIR" && eval "$generate") || fail "generate failed: $generate"
fi
before=$(cd "$DIR" && find . -mindepth 1 | sort)
sums_before=$(cd "$DIR" && for f in $unchanged; do cksum "$f"; done)
outside_before=$(find "$work" -mindepth 1 -maxdepth 1 | sort)

if [ -n "$address_space" ] && [ "$memory_factor" != 1 ]; then
  echo "hostile case $name: skipped in a sanitizer build (address-space-mib: $address_space)"
  exit 77
fi
eval "set -- $args"
start=$(date +%s%N)
(cd "$DIR" && { [ -z "$address_space" ] || ulimit -v $((address_space * 1024)); } &&
   exec /usr/bin/time -f '%M' -o "$work/rss" timeout -s KILL "$max_seconds" "$fmpc" "$@" \
   > "$work/stdout" 2> "$work/stderr" < /dev/null)
status=$?
elapsed_ms=$(( ($(date +%s%N) - start) / 1000000 ))
# /usr/bin/time reports the command's status; 137 is the timeout's KILL.
[ "$status" -ne 137 ] || fail "ran past $max_seconds s (hang or runaway)"
grep -q "Command terminated by signal 9" "$work/rss" && fail "ran past $max_seconds s (hang or runaway)"
if [ "$status" != "$exit_expected" ]; then
  echo "--- stderr:" >&2; head -c 4000 "$work/stderr" >&2
  fail "exit status $status, expected $exit_expected"
fi
rss_kib=$(grep -E '^[0-9]+$' "$work/rss" | tail -1)
if [ -n "$rss_kib" ] && [ "$rss_kib" -gt $((max_rss * memory_factor * 1024)) ]; then
  fail "peak memory $((rss_kib / 1024)) MiB, above $((max_rss * memory_factor)) MiB"
fi
stderr_bytes=$(wc -c < "$work/stderr")
[ "$stderr_bytes" -le 65536 ] || fail "stderr is $stderr_bytes bytes; diagnostics must cap their count and excerpts"
for needle in "${stderr_needles[@]}"; do
  grep -qF -- "$needle" "$work/stderr" || { echo "--- stderr:" >&2; head -c 4000 "$work/stderr" >&2; \
    fail "stderr lacks '$needle'"; }
done
for needle in "${stdout_needles[@]}"; do
  grep -qF -- "$needle" "$work/stdout" || fail "stdout lacks '$needle'"
done
if [ "$status" -ge 70 ] || grep -q "internal error\|AddressSanitizer\|runtime error:" "$work/stderr"; then
  fail "crashed or reported an internal error"
fi
after=$(cd "$DIR" && find . -mindepth 1 | sort)
expected_after=$( (echo "$before"; for f in $files; do echo "./$f"; d=$(dirname "$f"); \
  while [ "$d" != "." ]; do echo "./$d"; d=$(dirname "$d"); done; done) | grep -v '^$' | sort -u)
if [ "$(echo "$after" | grep -v '^$')" != "$(echo "$expected_after" | grep -v '^$')" ]; then
  fail "the run left files it should not have: $(diff <(echo "$expected_after") <(echo "$after") | grep '^>' | tr '\n' ' ')"
fi
[ "$(cd "$DIR" && for f in $unchanged; do cksum "$f"; done)" = "$sums_before" ] ||
  fail "the run changed one of: $unchanged"
outside_after=$(find "$work" -mindepth 1 -maxdepth 1 | grep -v -e "/stdout$" -e "/stderr$" -e "/rss$" | sort)
[ "$outside_after" = "$outside_before" ] || fail "the run wrote outside its folder: $outside_after"
echo "hostile case $name: ok (exit $status, ${elapsed_ms} ms, $((${rss_kib:-0} / 1024)) MiB)"
