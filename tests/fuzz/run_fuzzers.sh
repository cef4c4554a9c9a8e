#!/usr/bin/env bash
# Long fuzzing runs (docs/limits.md, "Fuzzing"): tests/fuzz/run_fuzzers.sh [--jobs K] BUILD_DIR SECONDS [TARGET...]
# BUILD_DIR was configured with CC=clang CXX=clang++ -DFMPC_FUZZ=ON (and -DFMPC_SANITIZE=ON). Each target runs for
# SECONDS with its seeds and dictionary; its corpus grows in BUILD_DIR/fuzz-corpus/TARGET and is kept between runs.
# --jobs K runs K processes per target, all targets at once (K x targets processes: size K to the machine's cores);
# the processes of a target share its corpus folder. Without --jobs, one process per target, one target after the
# other. The CPU seconds each target got are added up over runs in BUILD_DIR/fuzz-corpus/TARGET.cpu_seconds.
# One line per target: CPU seconds (this run and all runs), executions, exec/s, coverage; a finding stops that
# process and is left in BUILD_DIR/fuzz-corpus/TARGET-findings (make it a tests/hostile case); exit 1 then.
# Where the binaries were carried to another machine (bench/run_gpu.sh, section fuzz): FMPC_FUZZ_BINARIES names the
# folder holding fuzz_TARGET (default BUILD_DIR/tests/fuzz), FMPC_FUZZ_SEEDS a folder of TARGET/ seed folders made
# beforehand (default: copied here from the repository and ../shared/data).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
jobs=0
if [ "${1:-}" = "--jobs" ]; then
  jobs=$2
  shift 2
  [[ "$jobs" =~ ^[1-9][0-9]*$ ]] || { echo "--jobs needs a positive count" >&2; exit 2; }
fi
[ $# -ge 2 ] || { echo "usage: run_fuzzers.sh [--jobs K] BUILD_DIR SECONDS [TARGET...]" >&2; exit 2; }
build=$(cd "$1" && pwd)
seconds=$2
shift 2
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fmpc_language matlab_fis fll fcl scene_yaml gmsh obj vtk fzt csv lsp python_arguments)
binaries=${FMPC_FUZZ_BINARIES:-$build/tests/fuzz}
shared=$(cd "$root/.." && pwd)/shared/data

# fuzz_one TARGET PROCESS: one libFuzzer process; its log is fuzz-corpus/TARGET.PROCESS.log.
fuzz_one() {
  local name=$1 process=$2
  local corpus=$build/fuzz-corpus/$name findings=$build/fuzz-corpus/$name-findings
  local seeds=${FMPC_FUZZ_SEEDS:+$FMPC_FUZZ_SEEDS/$name}
  seeds=${seeds:-$build/fuzz-corpus/$name-seeds}
  local dict=()
  [ -f "$root/tests/fuzz/dict/$name.dict" ] && dict=(-dict="$root/tests/fuzz/dict/$name.dict")
  # fuzz_python_arguments reads its fixtures from the source tree and keeps the interpreter's objects to the end.
  if [ "$name" = python_arguments ]; then
    dict+=(-detect_leaks=0)
    export FMPC_FUZZ_FIXTURES="$root" ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
  fi
  local TIMEFORMAT='%U %S' status=0
  # bash's `time`: the process's user and system CPU seconds, into TARGET.PROCESS.cpu.
  { time "$binaries/fuzz_$name" "${dict[@]}" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -max_len=65536 -print_final_stats=1 -seed="$((process + 1))$RANDOM" -artifact_prefix="$findings/" \
      "$corpus" "$seeds" > "$build/fuzz-corpus/$name.$process.log" 2>&1 || status=$?; } \
    2> "$build/fuzz-corpus/$name.$process.cpu"
  return $status
}

# report TARGET PROCESSES STATUS: the target's line, and its CPU seconds added to the running total.
report() {
  local name=$1 processes=$2 status=$3 runs=0 rate=0 cpu=0 cov="" log n n_runs n_rate
  for ((n = 0; n < processes; n++)); do
    log=$build/fuzz-corpus/$name.$n.log
    # The last of the final stats (an embedded interpreter's exit can print them twice).
    n_runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1 || echo 0)
    n_rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1 || echo 0)
    n_runs=${n_runs:-0} n_rate=${n_rate:-0}
    runs=$((runs + n_runs))
    rate=$((rate + n_rate))
    cpu=$(awk -v sum="$cpu" '{ sum += $1 + $2 } END { printf "%d", sum }' "$build/fuzz-corpus/$name.$n.cpu")
    cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1 || true)
  done
  local total_file=$build/fuzz-corpus/$name.cpu_seconds total=0
  [ -f "$total_file" ] && total=$(cat "$total_file")
  total=$((total + cpu))
  echo "$total" > "$total_file"
  echo "fuzz_$name: $cpu CPU s in $processes x $seconds s (all runs: $total CPU s = $((total / 60)) CPU min), $runs executions, $rate exec/s, ${cov}, exit $status"
}

for name in "${targets[@]}"; do
  mkdir -p "$build/fuzz-corpus/$name" "$build/fuzz-corpus/$name-findings"
  [ -x "$binaries/fuzz_$name" ] || { echo "no $binaries/fuzz_$name (configure with -DFMPC_FUZZ=ON)" >&2; exit 2; }
  if [ -z "${FMPC_FUZZ_SEEDS:-}" ]; then
    mkdir -p "$build/fuzz-corpus/$name-seeds"
    cmake -DNAME="$name" -DSOURCE_DIR="$root" -DSHARED_DATA="$shared" -DOUT="$build/fuzz-corpus/$name-seeds" \
      -P "$root/tests/fuzz/copy_seeds.cmake"
  fi
done

failed=0
if [ "$jobs" -eq 0 ]; then
  for name in "${targets[@]}"; do
    status=0
    fuzz_one "$name" 0 || status=$?
    report "$name" 1 "$status"
    [ "$status" -eq 0 ] || { echo "finding: see $build/fuzz-corpus/$name-findings and $name.0.log"; exit 1; }
  done
  exit 0
fi

declare -A pids
for name in "${targets[@]}"; do
  for ((n = 0; n < jobs; n++)); do
    fuzz_one "$name" "$n" &
    pids[$name.$n]=$!
  done
done
for name in "${targets[@]}"; do
  status=0
  for ((n = 0; n < jobs; n++)); do
    wait "${pids[$name.$n]}" || status=$?
  done
  report "$name" "$jobs" "$status"
  if [ "$status" -ne 0 ]; then
    echo "finding: see $build/fuzz-corpus/$name-findings and its $name.*.log"
    failed=1
  fi
done
exit $failed
