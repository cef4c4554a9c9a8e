#!/usr/bin/env bash
# Long fuzzing runs (docs/limits.md, "Fuzzing"): tests/fuzz/run_fuzzers.sh BUILD_DIR SECONDS [TARGET...]
# BUILD_DIR was configured with CC=clang CXX=clang++ -DFMPC_FUZZ=ON (and -DFMPC_SANITIZE=ON). Each target runs for
# SECONDS with its seeds and dictionary; its corpus grows in BUILD_DIR/fuzz-corpus/TARGET and is kept between runs.
# One line per target: seconds, executions, exec/s, coverage; a finding stops the target and is left in
# BUILD_DIR/fuzz-corpus/TARGET-findings (make it a tests/hostile case).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=$(cd "$1" && pwd)
seconds=$2
shift 2
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fmpc_language matlab_fis scene_yaml gmsh obj vtk fzt csv)
shared=$(cd "$root/.." && pwd)/shared/data
for name in "${targets[@]}"; do
  corpus=$build/fuzz-corpus/$name
  seeds=$build/fuzz-corpus/$name-seeds
  findings=$build/fuzz-corpus/$name-findings
  mkdir -p "$corpus" "$seeds" "$findings"
  cmake -DNAME="$name" -DSOURCE_DIR="$root" -DSHARED_DATA="$shared" -DOUT="$seeds" \
    -P "$root/tests/fuzz/copy_seeds.cmake"
  dict=()
  [ -f "$root/tests/fuzz/dict/$name.dict" ] && dict=(-dict="$root/tests/fuzz/dict/$name.dict")
  log=$build/fuzz-corpus/$name.log
  status=0
  "$build/tests/fuzz/fuzz_$name" "${dict[@]}" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -max_len=65536 -print_final_stats=1 -artifact_prefix="$findings/" "$corpus" "$seeds" > "$log" 2>&1 || status=$?
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1)
  time_s=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  echo "fuzz_$name: ${seconds} s, ${runs} executions, ${time_s} exec/s, ${cov}, exit ${status}"
  [ "$status" -eq 0 ] || { echo "finding: see $findings and $log"; exit 1; }
done
