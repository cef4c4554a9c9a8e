#!/usr/bin/env bash
# GPU measurements. The GPU machine has CMake, nvcc and the CUDA libraries but none of the Debian packages, so this
# builds the FMPC_GPU_ONLY configuration (runtime/gpu/gpu_only.cmake), whose only third-party need is Eigen's
# headers, copied beforehand on the build machine:
#
#   bash bench/run_gpu.sh --prepare     # build machine: copy /usr/include/eigen3/Eigen to build-gpu-carry/eigen3
#   bash bench/run_gpu.sh               # GPU machine, from the repository root, with build-gpu-carry/ carried
#
# To spare the GPU machine its build (about 140 s), build the GPU-only configuration here (build_section's cmake line,
# plus ccache) and bundle it: GPU_PREBUILT=build-gpu-local FMPC=build-cuda/tools/fmpc bash bench/run_gpu.sh --prepare
# (FUZZ_BUILD=none leaves the fuzz targets out when the carry would pass 64 MiB).
#
# The device tool brings back at most 8 files from its $OUT, two folders deep: write elsewhere and pack, e.g.
#   D=$OUT; OUT=/tmp/gpu bash bench/run_gpu.sh --only tests,sanitizers; tar -C /tmp -czf $D/gpu.tgz gpu
#
# Sections (each appends to $OUT/summary.md, printed last):
#   build       configure + build, Release, sm_90, FMPC_GPU_ONLY=ON
#   simulator   gpu-labelled tests (CPU vs CUDA after 10,000 steps, bitwise reruns, batches, NaN location; GPU_TESTS="NAME
#               ..." runs only fmpc_gpu_tests' cases whose names contain one of these),
#               compute-sanitizer memcheck/racecheck/initcheck/synccheck on fmpc_gpu_tests' sanitizer_ smoke tests
#               (SANITIZER_SMOKES="NAME ...": those whose names contain one of these),
#               bench/sim (CPU threads vs CUDA float/double, graphs on/off, 1k..1M springs, batch of scenes,
#               a cohort of 1,000 demo-scene patients with their probes in one launch: row cuda-cohort)
#   laws        fmpc_sim_bench --fem-only at 120^3 cells for each law on each element kind (LAW_ELEMENTS, law:element
#               pairs; LAW_CELLS), float and double, semi-implicit Euler: element-steps/s (issue 26 item 7)
#   scenes      the carried fmpc (a CUDA build of the build machine with its libraries and fonts: --prepare bundles
#               $FMPC into build-gpu-carry/programs.tar.xz) runs the README's demo scene with backend auto (CUDA)
#               and cpu, and SOFA's liver scenes (implicit Euler: springs, fuzzy springs, co-rotational FEM as
#               liver-CUDA.scn) on CUDA and on the CPU; the demo's 12-patient cohort (--patients) on both,
#               cohort.csv compared; large boxes (240^3 springs, 120^3 FEM) end to end; outputs under $OUT/scenes
#   haptic      the carried fmpc_haptic_bench (bench/haptic, from the same CUDA build as the carried fmpc: --prepare
#               bundles it with fmpc) runs the 1 kHz haptic loop on the 20^3 block and on the meshed liver (--tissue
#               liver: rulesets/scenes/liver_meshed.yaml, SOFA's liver-smooth.obj carried) with the sphere tool, 30 s of wall
#               time per mode (HAPTIC_SECONDS), implicit Euler and explicit substeps, on CUDA and on the CPU: per-tick
#               latency p50/p99/max, real-time factor, the force curves (haptic/haptic_force_*.csv: each tick's mean
#               force and its tick-end force), haptic.md; on CUDA the explicit mode again with the tick-end force only
#               (--force end, one call per tick) and with contact damping (--contact-damping 1)
#   press       (only when asked: --only press) the carried fmpc_graded_press_bench (bench/graded, bundled with fmpc by
#               --prepare) presses SOFA's liver with the sphere of bench/scenes/liver_sphere_press.yaml on CUDA,
#               quadratic, the surface split to the field: graded and uniform meshes (PRESS_ROWS, PRESS_TIMEOUT), one
#               line each with the mesh, the force and the press's wall time (issue 28 item 3); logs in $OUT/press
#   multigpu    (only when asked: --only multigpu) the carried fmpc runs the demo's cohort of 1,000 patients (inputs
#               drawn uniformly within the ranges of liver_indentation_patients.csv, awk seed 13) on CUDA on one GPU
#               (--devices 0) and on every GPU of the machine (--devices all), checks the two cohort.csv equal in every
#               column but steps_per_second (a timing), and writes the speed-ups of the stepping, of stepping and
#               recording, and of the whole command into summary.md (issue 27 item 6: >= 1.8x on two GPUs);
#               outputs under $OUT/multigpu
#   setup       (only when asked: --only setup) bench/setup's fmpc_setup_bench on the GPU machine's cores: boxes of
#               60^3, 120^3 and 240^3 cells (issue 13: 100M springs set up in 20 s, 64 bytes per spring at peak)
#               with the model builder's breakdown and the simulators' peak, then 120^3 on one thread (same checksum)
#   profile     (only when asked: --only profile) Nsight Compute (ncu) on the kernels that bound the goals: the FEM
#               120^3 element and vertex passes (fmpc_sim_bench --fem-only), the carried fmpc's 240^3 springs box
#               and 20^3 small box, implicit Euler's CG kernels (the 20^3 FEM box's element products and fused
#               stages, SOFA's liver's one-block solve, each run's kernel durations); reports as text in
#               $OUT/profile_*.txt
#   fuzz        (only when asked: --only fuzz) the libFuzzer targets of the build machine's build-asan, bundled by
#               --prepare, FUZZ_JOBS processes each on the GPU machine's cores for FUZZ_SECONDS (default 540); the
#               corpora come back as $OUT/fuzz-corpus.tar.xz, which FUZZ_CORPUS=... --prepare carries to a next run;
#               FUZZ_TARGETS="fll fcl ..." runs only those
#   evaluator   bench/gpu/evaluator_gpu_bench.cu (nvcc alone): the generated CUDA evaluators (type-1 and interval
#               type-2, float and double) and table lookups (2-D double and float; 5-D double and float at 9^5,
#               7^5, 5^5; each in the grid and the sector-packed layout) on the liver rule base, each checked
#               against the CPU, then
#               timed; then the bench on a small batch under compute-sanitizer memcheck and racecheck. Its headers
#               come from --prepare (build-gpu-carry/evaluator, generated with the build machine's fmpc), as do
#               those of the gpu-labelled test gpu.generated_evaluator (simulator section: evaluators and tables)
#   baseline    (only when asked: --only baseline) this tree against a baseline commit, in the same call on the same
#               GPU (issue 25: within 3%). `BASELINE=<commit> BASELINE_FMPC=<that commit's CUDA build's fmpc> --prepare`
#               carries the commit's source (baseline-src.tar.xz) and bundles its fmpc as fmpc-baseline; here the
#               baseline's fmpc_sim_bench is built GPU-only beside this tree's, and each row runs alternately on the two
#               BASELINE_REPEATS times (default 3): small (the 20^3 box end to end: each tree's fmpc simulate on its own
#               bench/scenes/small_box_springs.yaml, steps/s), large (the 240^3 springs box, fmpc_sim_bench
#               --spring-cells 240), fem (--fem-only --fem-cells 120) and cohort (--cohort-only --cohort 1000), us per
#               step per fmpc_sim_bench row (BASELINE_SIM_BENCH=<the baseline's GPU-only fmpc_sim_bench built here> at
#               --prepare spares the GPU machine that build). BASELINE_ROWS picks rows (default small,cohort,fem,large). Medians and
#               the ratio this/baseline in baseline.md
# Other GPU benchmarks add their own section function below and call it from the list at the end.
#
# Results: $OUT (default ./out/gpu): configure/build logs, gpu_tests.log, sanitizer_*.log, sim_bench.{csv,md,log},
# device.txt, summary.md. Options: --skip-sanitizers, --quick (shorter benchmark), --evaluator-only (that section
# alone: no CMake build), --only LIST (comma-separated parts: tests, sanitizers, bench, laws, scenes, haptic, press, multigpu,
# evaluator, fuzz; the build runs when tests, sanitizers or bench are asked for; a second call on a warm machine reuses
# it). Exit status: 0 when every step passed.
set -u -o pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
CARRY="$ROOT/build-gpu-carry"

# The evaluator section's headers, generated by fmpc on the build machine (the GPU machine has no fmpc):
# build-gpu-carry/evaluator/{liver_evaluator.cuh, liver_it2_evaluator.cuh, liver_table*.h} and
# build-gpu-carry/evaluator/tests/*.{cuh,h} (tests/gpu/evaluator). fmpc is $FMPC, or the first of build*/tools/fmpc.
prepare_evaluator_headers() {
  local fmpc="${FMPC:-}"
  if [[ -z "$fmpc" ]]; then
    for candidate in "$ROOT"/build/tools/fmpc "$ROOT"/build*/tools/fmpc; do
      [[ -x "$candidate" ]] && { fmpc="$candidate"; break; }
    done
  fi
  if [[ -z "$fmpc" ]]; then
    echo "no fmpc binary (build fmpc first or set FMPC=...): the evaluator headers were not generated" >&2
    return 1
  fi
  local rules="$ROOT/rulesets/liver_fibrosis/mamdani.fis" dir="$CARRY/evaluator"
  mkdir -p "$dir"
  "$fmpc" compile "$rules" --target cuda --namespace liver_evaluator -o "$dir/liver_evaluator.cuh" &&
    "$fmpc" compile "$ROOT/rulesets/liver_fibrosis/it2.fis" --target cuda --namespace liver_it2_evaluator \
      -o "$dir/liver_it2_evaluator.cuh" &&
    "$fmpc" compile "$rules" --target table --fix HCV=10 --fix ALD=22 --fix NAFLD=6 --vary HBV:65 --vary CLD:65 \
      --max-error 75 --namespace liver_table2 -o "$dir/liver_table2.h" &&
    "$fmpc" compile "$rules" --target table --fix HCV=10 --fix ALD=22 --fix NAFLD=6 --vary HBV:65 --vary CLD:65 \
      --max-error 75 --precision float --namespace liver_table2f -o "$dir/liver_table2f.h" &&
    "$fmpc" compile "$rules" --target table --vary HCV:9 --vary HBV:9 --vary ALD:9 --vary CLD:9 --vary NAFLD:9 \
      --max-error 75 --namespace liver_table5 -o "$dir/liver_table5.h" &&
    "$fmpc" compile "$rules" --target table --vary HCV:9 --vary HBV:9 --vary ALD:9 --vary CLD:9 --vary NAFLD:9 \
      --max-error 75 --precision float --namespace liver_table5f -o "$dir/liver_table5f.h" &&
    "$fmpc" compile "$rules" --target table --vary HCV:7 --vary HBV:7 --vary ALD:7 --vary CLD:7 --vary NAFLD:7 \
      --max-error 75 --namespace liver_table5r7 -o "$dir/liver_table5r7.h" &&
    "$fmpc" compile "$rules" --target table --vary HCV:5 --vary HBV:5 --vary ALD:5 --vary CLD:5 --vary NAFLD:5 \
      --max-error 75 --namespace liver_table5r5 -o "$dir/liver_table5r5.h" ||
    { echo "fmpc compile failed: the evaluator headers are incomplete" >&2; return 1; }
  # The headers of tests/gpu/evaluator (ctest gpu.generated_evaluator), which the GPU-only build reads from here;
  # the NAME=RULE_FILE lines of that folder's CMakeLists.txt are the list.
  mkdir -p "$dir/tests"
  local entry entries
  entries=$(grep -E '^ +[a-z0-9_]+=[^ ]+\.fis\)?$' "$ROOT/tests/gpu/evaluator/CMakeLists.txt" | tr -d ' )')
  [[ -n "$entries" ]] || { echo "no rule files listed in tests/gpu/evaluator/CMakeLists.txt" >&2; return 1; }
  for entry in $entries; do
    "$fmpc" compile "$ROOT/${entry#*=}" --target cuda --namespace "${entry%%=*}" -o "$dir/tests/${entry%%=*}.cuh" \
      > /dev/null || { echo "fmpc compile ${entry#*=} failed" >&2; return 1; }
  done
  # Its tables: NAME=BINDINGS lines, INPUT:POINTS varies an input, INPUT=VALUE fixes it.
  local name binding arguments bindings
  entries=$(grep -E '^ +[a-z0-9_]+=[A-Z][^ ]*\)?$' "$ROOT/tests/gpu/evaluator/CMakeLists.txt" | tr -d ' )')
  for entry in $entries; do
    name="${entry%%=*}"
    arguments=()
    IFS=',' read -r -a bindings <<< "${entry#*=}"
    for binding in "${bindings[@]}"; do
      if [[ "$binding" == *:* ]]; then arguments+=(--vary "$binding"); else arguments+=(--fix "$binding"); fi
    done
    "$fmpc" compile "$rules" --target table "${arguments[@]}" --max-error 75 --namespace "$name" \
      -o "$dir/tests/$name.h" > /dev/null || { echo "fmpc compile --target table for $name failed" >&2; return 1; }
  done
  echo "generated the evaluator section's headers in $dir with $fmpc"
}

# Programs built here and run on the GPU machine, which has none of the Debian libraries they link: each goes into
# build-gpu-carry/programs with every shared library ldd names (glibc and its loader included, so the GPU machine's
# own glibc version does not matter; the CUDA driver's libcuda is the GPU machine's and is not carried) and a
# wrapper bin/NAME that starts it through the carried loader. DejaVu fonts and a fontconfig file come along for
# cairo and pango. The folder is packed into build-gpu-carry/programs.tar.xz (the carry limit is 64 MiB in all).
PROGRAMS="$CARRY/programs"
bundle_program() {  # bundle_program BINARY [NAME]
  local binary=$1 name=${2:-$(basename "$1")}
  mkdir -p "$PROGRAMS/libexec" "$PROGRAMS/lib" "$PROGRAMS/bin"
  cp "$binary" "$PROGRAMS/libexec/$name" && strip --strip-debug "$PROGRAMS/libexec/$name" || return 1
  local library
  for library in $(ldd "$binary" | awk '$2 == "=>" && $3 ~ /^\// { print $3 } $1 ~ /^\/.*ld-linux/ { print $1 }'); do
    case "$(basename "$library")" in libcuda.so*) continue ;; esac
    [[ -f "$PROGRAMS/lib/$(basename "$library")" ]] || cp -L "$library" "$PROGRAMS/lib/" || return 1
  done
  cat > "$PROGRAMS/bin/$name" <<WRAPPER
#!/bin/sh
# $name built on the build machine, with its libraries (bench/run_gpu.sh, bundle_program).
here=\$(cd "\$(dirname "\$0")/.." && pwd)
if [ -d "\$here/fonts" ]; then
  mkdir -p "\${TMPDIR:-/tmp}/fmpc-fontconfig"
  printf '<fontconfig><dir>%s/fonts</dir><cachedir>%s</cachedir></fontconfig>\\n' "\$here" \\
    "\${TMPDIR:-/tmp}/fmpc-fontconfig" > "\${TMPDIR:-/tmp}/fmpc-fontconfig/fonts.conf"
  export FONTCONFIG_FILE="\${TMPDIR:-/tmp}/fmpc-fontconfig/fonts.conf"
fi
exec "\$here/lib/$(basename "$(ls "$PROGRAMS"/lib/ld-linux* | head -1)")" --library-path "\$here/lib" "\$here/libexec/$name" "\$@"
WRAPPER
  chmod +x "$PROGRAMS/bin/$name"
}

# The scenes section's fmpc (a CUDA build: $FMPC, e.g. -DFMPC_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90) with its fonts,
# and SOFA's liver mesh and surface (the haptic section's meshed liver) when ../shared/data/sofa-liver exists.
prepare_scenes() {
  local fmpc="${FMPC:-}"
  [[ -n "$fmpc" && -x "$fmpc" ]] || { echo "set FMPC=path/to/a CUDA build's fmpc for the scenes section" >&2; return 1; }
  bundle_program "$fmpc" fmpc || return 1
  # The haptic section's benchmark from the same build (HAPTIC_BENCH=... names another).
  local haptic="${HAPTIC_BENCH:-$(dirname "$fmpc")/../bench/haptic/fmpc_haptic_bench}"
  if [[ -x "$haptic" ]]; then
    bundle_program "$haptic" fmpc_haptic_bench || return 1
  else
    echo "no $haptic (build the target fmpc_haptic_bench): the haptic section will not run" >&2
  fi
  # The press section's benchmark, likewise (PRESS_BENCH=... names another).
  local press="${PRESS_BENCH:-$(dirname "$fmpc")/../bench/graded/fmpc_graded_press_bench}"
  if [[ -x "$press" ]]; then
    bundle_program "$press" fmpc_graded_press_bench || return 1
  else
    echo "no $press (build the target fmpc_graded_press_bench): the press section will not run" >&2
  fi
  mkdir -p "$PROGRAMS/fonts"
  cp /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf /usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf \
    "$PROGRAMS/fonts/" || { echo "no DejaVu fonts (Debian fonts-dejavu-core)" >&2; return 1; }
  if [[ -d "$ROOT/../shared/data/sofa-liver" ]]; then
    mkdir -p "$CARRY/sofa-liver"
    cp "$ROOT/../shared/data/sofa-liver/liver.msh" "$ROOT/../shared/data/sofa-liver/liver-smooth.obj" "$CARRY/sofa-liver/"
  fi
  echo "bundled $fmpc as $PROGRAMS/bin/fmpc"
}

# A GPU-only build made on the build machine (GPU_PREBUILT=DIR, configured as build_section does, with the targets
# fmpc_gpu_tests, fmpc_sim_bench and fmpc_setup_bench built): bundled so that the GPU machine skips its own build
# (about 140 s of device time). Its commit goes beside it; build_section says which commit ran.
prepare_prebuilt() {
  local build=$1 target path
  for target in tests/gpu/fmpc_gpu_tests bench/sim/fmpc_sim_bench bench/setup/fmpc_setup_bench; do
    path="$build/$target"
    if [[ ! -x "$path" ]]; then
      [[ $target == bench/setup/* ]] && { echo "no $path: the setup section will build nothing and fail" >&2; continue; }
      echo "no $path: build it in $build first (GPU_PREBUILT)" >&2
      return 1
    fi
    bundle_program "$path" || return 1
  done
  git -C "$ROOT" rev-parse --short HEAD > "$PROGRAMS/prebuilt-commit.txt"
  [[ -z "$(git -C "$ROOT" status --porcelain --untracked-files=no)" ]] || echo "(with uncommitted changes)" >> "$PROGRAMS/prebuilt-commit.txt"
  echo "bundled the GPU-only build in $build"
}

# The fuzz section's libFuzzer targets from $FUZZ_BUILD (default build-asan: CC=clang CXX=clang++ -DFMPC_FUZZ=ON
# -DFMPC_SANITIZE=ON) and their seeds (tests/fuzz/copy_seeds.cmake, here where ../shared/data is): every target that
# build has (fuzz_fll and fuzz_fcl were once left out of a fixed list here), so a new target needs no edit here.
prepare_fuzz() {
  local build="${FUZZ_BUILD:-$ROOT/build-asan}" program name count=0
  for program in "$build"/tests/fuzz/fuzz_*; do
    [[ -f "$program" && -x "$program" ]] || continue
    name=${program##*/fuzz_}
    bundle_program "$program" || return 1
    mkdir -p "$PROGRAMS/seeds/$name"
    cmake -DNAME="$name" -DSOURCE_DIR="$ROOT" -DSHARED_DATA="$ROOT/../shared/data" -DOUT="$PROGRAMS/seeds/$name" \
      -P "$ROOT/tests/fuzz/copy_seeds.cmake" || return 1
    count=$((count + 1))
  done
  [[ $count -gt 0 ]] || { echo "no fuzz targets in $build/tests/fuzz: the fuzz section will not run" >&2; return 0; }
  echo "bundled $count fuzz targets from $build"
}

if [[ "${1:-}" == "--prepare" ]]; then
  mkdir -p "$CARRY/eigen3"
  rm -rf "$CARRY/eigen3/Eigen"
  cp -r /usr/include/eigen3/Eigen "$CARRY/eigen3/" || exit 1
  echo "copied Eigen headers to $CARRY/eigen3 ($(du -sh "$CARRY" | cut -f1)); carry build-gpu-carry to the GPU machine"
  prepare_evaluator_headers || exit 1
  rm -rf "$PROGRAMS" "$PROGRAMS.tar.xz"
  # Without a CUDA build's fmpc (FMPC unset) the scenes section cannot run; the tests, sanitizers and bench can.
  if [[ -n "${FMPC:-}" ]]; then
    prepare_scenes || exit 1
  else
    echo "FMPC is not set: no fmpc bundled, the scenes section will not run (tests, sanitizers, bench will)"
  fi
  if [[ -n "${GPU_PREBUILT:-}" ]]; then
    prepare_prebuilt "$GPU_PREBUILT" || exit 1
  fi
  rm -f "$CARRY/baseline-src.tar.xz"
  if [[ -n "${BASELINE:-}" ]]; then
    [[ -n "${BASELINE_FMPC:-}" && -x "${BASELINE_FMPC:-}" ]] ||
      { echo "BASELINE=$BASELINE needs BASELINE_FMPC=<a CUDA build of $BASELINE>/tools/fmpc" >&2; exit 1; }
    git -C "$ROOT" archive --format=tar --prefix=baseline-src/ "$BASELINE" | xz -T0 > "$CARRY/baseline-src.tar.xz" ||
      { echo "git archive $BASELINE failed" >&2; exit 1; }
    git -C "$ROOT" rev-parse --short "$BASELINE" > "$CARRY/baseline-commit.txt"
    bundle_program "$BASELINE_FMPC" fmpc-baseline || exit 1
    # The baseline's GPU-only fmpc_sim_bench built here (optional: without it the GPU machine builds it).
    if [[ -n "${BASELINE_SIM_BENCH:-}" ]]; then
      bundle_program "$BASELINE_SIM_BENCH" fmpc_sim_bench-baseline || exit 1
    fi
    echo "carrying the source of $BASELINE and its fmpc ($BASELINE_FMPC) for the baseline section"
  fi
  prepare_fuzz || exit 1
  rm -f "$CARRY/fuzz-corpus.tar.xz"
  if [[ -n "${FUZZ_CORPUS:-}" ]]; then
    cp "$FUZZ_CORPUS" "$CARRY/fuzz-corpus.tar.xz" || exit 1
    echo "carrying the fuzz corpus $FUZZ_CORPUS"
  fi
  if [[ -d "$PROGRAMS" ]]; then
    tar -C "$CARRY" -cJf "$PROGRAMS.tar.xz" programs && rm -rf "$PROGRAMS" || exit 1
  fi
  size=$(du -sm "$CARRY" | cut -f1)
  echo "build-gpu-carry: $size MiB (programs.tar.xz $(du -sh "$PROGRAMS.tar.xz" 2>/dev/null | cut -f1 || echo none))"
  [[ $size -lt 64 ]] || { echo "build-gpu-carry is over the carry limit of 64 MiB" >&2; exit 1; }
  exit 0
fi

SKIP_SANITIZERS=0
QUICK=0
EVALUATOR_ONLY=0
ONLY="tests,sanitizers,bench,laws,scenes,haptic,evaluator"
usage="usage: bash bench/run_gpu.sh [--prepare | --skip-sanitizers | --quick | --evaluator-only | --only LIST]"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --skip-sanitizers) SKIP_SANITIZERS=1 ;;
    --quick) QUICK=1 ;;
    --evaluator-only) EVALUATOR_ONLY=1 ;;
    --only)
      [[ $# -ge 2 ]] || { echo "$usage" >&2; exit 2; }
      ONLY="$2"
      shift
      for part in ${ONLY//,/ }; do
        case "$part" in
          tests | sanitizers | bench | laws | scenes | haptic | press | multigpu | evaluator | fuzz | setup | profile | baseline) ;;
          *) echo "--only: unknown part '$part' (tests, sanitizers, bench, laws, scenes, haptic, press, multigpu, evaluator, fuzz, setup, profile, baseline)" >&2
             exit 2 ;;
        esac
      done
      ;;
    *) echo "$usage" >&2; exit 2 ;;
  esac
  shift
done
# wanted PART: whether --only asked for it.
wanted() { [[ ",$ONLY," == *",$1,"* ]]; }
[[ $EVALUATOR_ONLY -eq 1 ]] && ONLY="evaluator"

OUT="${OUT:-$ROOT/out/gpu}"
mkdir -p "$OUT"
BUILD="${FMPC_GPU_BUILD:-$ROOT/build-gpu-device}"
UNPACKED="$BUILD/programs"
SUMMARY="$OUT/summary.md"
JOBS=$(nproc 2>/dev/null || echo 4)
FAILED=0
: > "$SUMMARY"

section() {
  echo
  echo "=== $1"
  printf '\n## %s\n\n' "$1" >> "$SUMMARY"
}
record() { echo "$1" | tee -a "$SUMMARY"; }
fail() {
  record "FAILED: $1"
  FAILED=1
}

device_info() {
  {
    date -u '+%Y-%m-%d %H:%M:%S UTC'
    uname -a
    nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv 2>&1 || true
    /usr/local/cuda/bin/nvcc --version 2>&1 | tail -2 || true
    cmake --version | head -1
    lscpu 2>/dev/null | grep -E 'Model name|^CPU\(s\)' || true
  } > "$OUT/device.txt"
  record "machine: $(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1 || echo 'no nvidia-smi'), $(nproc) CPU threads, $(date -u '+%Y-%m-%d')"
}

# place_program PROGRAM PATH: PATH (a build's binary path) starts the carried PROGRAM (bundle_program's wrapper, which
# finds its libraries from its own location, so it cannot be a symlink).
place_program() {
  mkdir -p "$(dirname "$2")"
  printf '#!/bin/sh\nexec "%s" "$@"\n' "$UNPACKED/bin/$1" > "$2" && chmod +x "$2"
}

PREBUILT=0
build_section() {
  # A build carried from the build machine (--prepare with GPU_PREBUILT) instead of this machine's own.
  if unpack_programs && [[ -x "$UNPACKED/bin/fmpc_gpu_tests" ]]; then
    section "build: carried GPU-only build (commit $(tr '\n' ' ' < "$UNPACKED/prebuilt-commit.txt"))"
    local target
    for target in tests/gpu/fmpc_gpu_tests bench/sim/fmpc_sim_bench bench/setup/fmpc_setup_bench; do
      [[ -x "$UNPACKED/bin/$(basename "$target")" ]] || continue
      place_program "$(basename "$target")" "$BUILD/$target"
    done
    PREBUILT=1
    record "build: carried (the gpu-labelled ctest cases other than fmpc_gpu_tests do not run)"
    return 0
  fi
  section "build (FMPC_GPU_ONLY, Release, sm_90)"
  if [[ ! -f "$CARRY/eigen3/Eigen/Sparse" ]]; then
    fail "no Eigen headers in $CARRY/eigen3: run 'bash bench/run_gpu.sh --prepare' on the build machine and carry build-gpu-carry"
    return 1
  fi
  local generator=()
  if command -v ninja > /dev/null; then generator=(-G Ninja); fi
  export PATH="/usr/local/cuda/bin:$PATH"
  if ! cmake -S "$ROOT" -B "$BUILD" ${generator[@]+"${generator[@]}"} -DFMPC_GPU_ONLY=ON -DFMPC_CUDA=ON \
      -DCMAKE_CUDA_ARCHITECTURES=90 -DCMAKE_BUILD_TYPE=Release -DFMPC_EIGEN_INCLUDE_DIR="$CARRY/eigen3" \
      > "$OUT/configure.log" 2>&1; then
    tail -30 "$OUT/configure.log"
    fail "configure (see configure.log)"
    return 1
  fi
  if ! cmake --build "$BUILD" -j "$JOBS" > "$OUT/build.log" 2>&1; then
    grep -E 'error|Error' "$OUT/build.log" | head -40
    fail "build (see build.log)"
    return 1
  fi
  record "build: ok"
}

simulator_section() {
  if wanted tests; then
  section "simulator: GPU tests"
  # GPU_TESTS="NAME ...": only the fmpc_gpu_tests cases whose names contain one of these (fmpc_gpu_tests --list).
  if [[ -n "${GPU_TESTS:-}" || $PREBUILT -eq 1 ]]; then
    # shellcheck disable=SC2086
    "$BUILD/tests/gpu/fmpc_gpu_tests" ${GPU_TESTS:-} > "$OUT/gpu_tests.log" 2>&1
  else
    (cd "$BUILD" && ctest -L gpu --output-on-failure -V) > "$OUT/gpu_tests.log" 2>&1
  fi
  local status=$?
  grep -E '\[ (PASS|FAIL|SKIP) \]|[0-9]+ passed, |max \|GPU - CPU\||GPU step|FAILED: ' "$OUT/gpu_tests.log" \
    | sed -E 's/^[0-9]+: *//' | tee -a "$SUMMARY"
  grep -q 'SKIPPED: ' "$OUT/gpu_tests.log" && fail "GPU tests skipped: no usable CUDA device"
  [[ $status -eq 0 ]] || fail "ctest -L gpu (see gpu_tests.log)"
  fi

  if wanted sanitizers; then
  section "simulator: compute-sanitizer"
  if [[ $SKIP_SANITIZERS -eq 1 ]]; then
    record "skipped (--skip-sanitizers)"
  else
    local sanitizer
    sanitizer=$(command -v compute-sanitizer || ls /usr/local/cuda/bin/compute-sanitizer \
      /usr/local/cuda/compute-sanitizer/compute-sanitizer 2>/dev/null | head -1)
    if [[ -z "$sanitizer" ]]; then
      fail "compute-sanitizer not found"
    else
      # Each smoke test (fmpc_gpu_tests --list: the names that start with sanitizer_) under each of the four tools in
      # a process of its own, all at once (racecheck alone takes minutes on the cooperative CG), each under
      # SANITIZER_SECONDS (default 480): a pair cut off is reported as such. Logs: sanitizer_TOOL_TEST.log.
      # SANITIZER_SMOKES="NAME ...": only the smoke tests whose names contain one of these.
      local tool smoke filter="${SANITIZER_SMOKES:-}"
      local -a smokes
      mapfile -t smokes < <("$BUILD/tests/gpu/fmpc_gpu_tests" --list | grep -E '^sanitizer_' \
        | grep -E "${filter// /|}")
      [[ ${#smokes[@]} -gt 0 ]] || fail "no sanitizer smoke tests in fmpc_gpu_tests --list"
      local -A pids=()
      for tool in memcheck racecheck initcheck synccheck; do
        local extra=()
        [[ $tool == memcheck ]] && extra=(--leak-check full)
        for smoke in "${smokes[@]}"; do
          timeout "${SANITIZER_SECONDS:-480}" "$sanitizer" --tool "$tool" ${extra[@]+"${extra[@]}"} --error-exitcode 99 \
            "$BUILD/tests/gpu/fmpc_gpu_tests" "$smoke" > "$OUT/sanitizer_${tool}_$smoke.log" 2>&1 &
          pids[$tool/$smoke]=$!
        done
      done
      for tool in memcheck racecheck initcheck synccheck; do
        for smoke in "${smokes[@]}"; do
          wait "${pids[$tool/$smoke]}"
          local rc=$? log="$OUT/sanitizer_${tool}_$smoke.log"
          local errors
          errors=$(grep -E 'ERROR SUMMARY|RACECHECK SUMMARY' "$log" | tail -1)
          if [[ $rc -eq 124 ]]; then
            fail "$tool $smoke: cut off after ${SANITIZER_SECONDS:-480} s"
          elif [[ $rc -eq 0 ]] && grep -q '\[ PASS \]' "$log"; then
            record "$tool $smoke: ok (${errors:-no summary line})"
          else
            fail "$tool $smoke: exit $rc (${errors:-see sanitizer_${tool}_$smoke.log})"
          fi
        done
      done
    fi
  fi
  fi

  wanted bench || return 0
  section "simulator: benchmark"
  local args=(--out "$OUT")
  [[ $QUICK -eq 1 ]] && args+=(--quick)
  # Implicit Euler's rows (issue 27 item 3) at SOFA's liver settings need its mesh: beside the repository, or carried.
  local liver
  liver=$(sofa_liver_file liver.msh)
  if [[ -f "$liver" ]]; then
    args+=(--liver "$liver")
  else
    record "sim_bench: SOFA liver implicit rows skipped (no liver.msh; bench/run_gpu.sh --prepare carries it)"
  fi
  if "$BUILD/bench/sim/fmpc_sim_bench" "${args[@]}" > "$OUT/sim_bench.log" 2>&1; then
    record "sim_bench: ok (sim_bench.csv, sim_bench.md)"
  else
    tail -5 "$OUT/sim_bench.log"
    fail "sim_bench (see sim_bench.log)"
  fi
}

# One scene with `fmpc simulate` on a backend; prints the run's report into the log.
# Frames stay in $BUILD/scenes (too many files to bring back); $OUT/scenes/NAME keeps the log, summary, CSV and plot.
run_scene() {
  local scene="$1" backend="$2" name="$3"
  shift 3
  "$UNPACKED/bin/fmpc" simulate "$scene" --backend "$backend" "$@" -o "$BUILD/scenes/$name" > "$OUT/scenes/$name.log" 2>&1
  local status=$?
  mkdir -p "$OUT/scenes/$name"
  cp "$BUILD/scenes/$name"/{summary.json,time_series.csv,force_displacement.png} "$OUT/scenes/$name/" 2>/dev/null
  ls "$BUILD/scenes/$name" | wc -l > "$OUT/scenes/$name/file_count.txt"
  return $status
}

# A summary.json field, without a JSON tool on the GPU machine.
json_field() { grep -o "\"$2\": *[^,}]*" "$1" | head -1 | sed -E 's/.*: *//; s/"//g'; }

scenes_section() {
  section "scenes: fmpc simulate on CUDA and on the CPU"
  need_program fmpc || return 1
  mkdir -p "$OUT/scenes" "$BUILD/scenes"
  local demo="$ROOT/rulesets/scenes/liver_indentation.yaml"
  run_scene "$demo" auto demo_auto || fail "demo with backend auto (see scenes/demo_auto.log)"
  grep -q "backend auto: running on CUDA" "$OUT/scenes/demo_auto.log" || fail "backend auto did not pick CUDA"
  run_scene "$demo" cpu demo_cpu || fail "demo on the CPU (see scenes/demo_cpu.log)"
  # SOFA's liver (implicit Euler): its mesh sits beside the repository as ../shared/data/sofa-liver.
  local sofa liver
  liver=$(sofa_liver_file liver.msh)
  for sofa in sofa_liver_springs sofa_liver_fuzzy sofa_liver_fem; do
    if [[ -f "$liver" ]]; then
      run_scene "$ROOT/rulesets/scenes/$sofa.yaml" cuda "${sofa}_cuda" || fail "$sofa on CUDA (see scenes/${sofa}_cuda.log)"
      run_scene "$ROOT/rulesets/scenes/$sofa.yaml" cpu "${sofa}_cpu" || fail "$sofa on the CPU (see scenes/${sofa}_cpu.log)"
    else
      record "$sofa: skipped (no liver.msh)"
    fi
  done
  # Large meshes end to end (issues 10 and 13): the stepping rate from summary.json, no frames. LARGE_STEPS=0 skips
  # them (their set-up takes about a minute).
  if [[ "${LARGE_STEPS:-1000}" != 0 ]]; then
    run_scene "$ROOT/bench/scenes/large_box_springs.yaml" cuda large_box_springs --steps "${LARGE_STEPS:-1000}" ||
      fail "large_box_springs on CUDA (see scenes/large_box_springs.log)"
    run_scene "$ROOT/bench/scenes/large_box_fem.yaml" cuda large_box_fem --steps "${LARGE_STEPS:-1000}" ||
      fail "large_box_fem on CUDA (see scenes/large_box_fem.log)"
  fi
  # The small mesh end to end (issue 13: 300,000 steps/s), the whole scene with its probe and 100 samples.
  run_scene "$ROOT/bench/scenes/small_box_springs.yaml" cuda small_box_springs ||
    fail "small_box_springs on CUDA (see scenes/small_box_springs.log)"
  local large
  for large in small_box_springs large_box_springs large_box_fem; do
    local summary="$OUT/scenes/$large/summary.json"
    [[ -f "$summary" ]] || continue
    local rate springs tetrahedra
    rate=$(json_field "$summary" steps_per_second)
    springs=$(json_field "$summary" springs)
    tetrahedra=$(json_field "$summary" tetrahedra)
    record "$large: $(json_field "$summary" vertices) vertices, ${springs:-0} springs, ${tetrahedra:-0} tetrahedra, $(json_field "$summary" steps) steps, $rate steps/s = $(awk -v r="$rate" -v s="${springs:-0}" 'BEGIN { printf "%.3g", r * s }') spring-steps/s, $(awk -v r="$rate" -v t="${tetrahedra:-0}" 'BEGIN { printf "%.3g", r * t }') tetrahedron-steps/s; setup and wall time in scenes/$large.log"
  done
  record "| run | backend | model | steps | wall s | steps/s | max displacement m | probe force N | inverted | files |"
  record "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
  local run
  for run in demo_auto demo_cpu sofa_liver_springs_cuda sofa_liver_springs_cpu sofa_liver_fuzzy_cuda sofa_liver_fuzzy_cpu \
      sofa_liver_fem_cuda sofa_liver_fem_cpu; do
    local summary="$OUT/scenes/$run/summary.json"
    [[ -f "$summary" ]] || continue
    record "| $run | $(json_field "$summary" backend) | $(json_field "$summary" model) | $(json_field "$summary" steps) | $(json_field "$summary" wall_time_s) | $(json_field "$summary" steps_per_second) | $(json_field "$summary" max_displacement_m) | $(json_field "$summary" final_force_N) | $(json_field "$summary" inverted_elements) | $(cat "$OUT/scenes/$run/file_count.txt") |"
  done
  [[ -f "$OUT/scenes/demo_auto/force_displacement.png" ]] || fail "the CUDA demo wrote no force_displacement.png"
  # A cohort (docs/cohorts.md): the demo's 12 patients in one CUDA batch and side by side on the CPU. The backends
  # give the same bits, so cohort.csv agrees in every column but the last (steps_per_second).
  local backend patients="$ROOT/rulesets/scenes/liver_indentation_patients.csv"
  for backend in cuda cpu; do
    "$UNPACKED/bin/fmpc" simulate "$demo" --backend "$backend" --patients "$patients" -o "$BUILD/scenes/cohort_$backend" \
      > "$OUT/scenes/cohort_$backend.log" 2>&1 || fail "cohort on $backend (see scenes/cohort_$backend.log)"
    mkdir -p "$OUT/scenes/cohort_$backend"
    cp "$BUILD/scenes/cohort_$backend"/{cohort.csv,cohort_force_displacement.png} "$OUT/scenes/cohort_$backend/" 2>/dev/null
    record "cohort on $backend: $(grep -E '^ *(stepping|whole command)' "$OUT/scenes/cohort_$backend.log" | sed 's/^ *//' | tr '\n' ';')"
  done
  if [[ -f "$OUT/scenes/cohort_cuda/cohort.csv" ]] &&
      cmp -s <(cut -d, -f1-15 "$OUT/scenes/cohort_cuda/cohort.csv") <(cut -d, -f1-15 "$OUT/scenes/cohort_cpu/cohort.csv"); then
    record "cohort: CUDA and CPU cohort.csv equal in every column but steps_per_second (12 patients)"
  else
    fail "cohort: CUDA and CPU cohort.csv differ (scenes/cohort_{cuda,cpu}/cohort.csv)"
  fi
}

# The haptic and press sections (haptic_section, press_section).
source "$ROOT/bench/run_gpu_tool_sections.sh"

# A cohort over every GPU of the machine (issue 27 item 6; docs/cohorts.md, "Every GPU of a node"): the demo's 1,000
# patients on one GPU and on all of them, one process each time (fmpc simulate --devices).
multigpu_section() {
  section "multigpu: the demo's 1,000-patient cohort on one GPU and on every GPU (fmpc simulate --devices)"
  need_program fmpc || return 1
  local gpus
  gpus=$(nvidia-smi -L 2>/dev/null | grep -c '^GPU ')
  record "GPUs: $gpus ($(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | sort | uniq -c | sed -E 's/^ +//' | paste -sd ';' -))"
  [[ $gpus -ge 2 ]] || record "only $gpus GPU: 'all' is that one GPU, so the speed-up below is about 1 (run on a machine of two or more)"
  mkdir -p "$OUT/multigpu" "$BUILD/multigpu"
  local demo="$ROOT/rulesets/scenes/liver_indentation.yaml" patients="$BUILD/multigpu/patients_1000.csv"
  # Uniform within each input's range over the demo's 12 patients (HCV 5-26, HBV 5-24, ALD 5-40, CLD 5-21, NAFLD 5-32).
  awk 'BEGIN { srand(13); print "label,HCV,HBV,ALD,CLD,NAFLD"
               for (p = 1; p <= 1000; ++p)
                 printf "P%04d,%.3f,%.3f,%.3f,%.3f,%.3f\n", p, 5 + 21 * rand(), 5 + 19 * rand(), 5 + 35 * rand(),
                        5 + 16 * rand(), 5 + 27 * rand() }' > "$patients"
  cp "$patients" "$OUT/multigpu/"
  local run devices
  for run in one all; do
    devices=$([[ $run == one ]] && echo 0 || echo all)
    rm -rf "$BUILD/multigpu/$run"
    if "$UNPACKED/bin/fmpc" simulate "$demo" --backend cuda --patients "$patients" --devices "$devices" \
        -o "$BUILD/multigpu/$run" > "$OUT/multigpu/$run.log" 2>&1; then
      cp "$BUILD/multigpu/$run/cohort.csv" "$OUT/multigpu/cohort_$run.csv"
      record "--devices $devices: $(grep -E '^  (stepping|whole command)' "$OUT/multigpu/$run.log" | sed -E 's/^ +//' | paste -sd ';' -)"
    else
      tail -5 "$OUT/multigpu/$run.log"
      fail "cohort with --devices $devices (see multigpu/$run.log)"
    fi
  done
  [[ -f "$OUT/multigpu/cohort_one.csv" && -f "$OUT/multigpu/cohort_all.csv" ]] || return 1
  if cmp -s <(cut -d, -f1-15 "$OUT/multigpu/cohort_one.csv") <(cut -d, -f1-15 "$OUT/multigpu/cohort_all.csv"); then
    record "cohort.csv: one GPU and $gpus GPUs equal in every column but steps_per_second ($(($(wc -l < "$OUT/multigpu/cohort_one.csv") - 1)) patients)"
  else
    fail "cohort.csv differs between one GPU and all (multigpu/cohort_{one,all}.csv)"
  fi
  # Seconds from the report: the stepping, stepping and recording, the whole command.
  seconds() {
    case "$2" in
      stepping) grep -E '^  stepping' "$1" | sed -E 's/.*checks included\): ([0-9.e+-]+) s.*/\1/' ;;
      recording) grep -E '^  whole command' "$1" | sed -E 's/.*stepping and recording ([0-9.e+-]+) s.*/\1/' ;;
      command) grep -E '^  whole command' "$1" | sed -E 's/^  whole command: ([0-9.e+-]+) s.*/\1/' ;;
    esac
  }
  local what one all label
  record ""
  record "| $gpus GPUs against one | one GPU s | all s | speed-up |"
  record "| --- | --- | --- | --- |"
  for what in stepping recording command; do
    one=$(seconds "$OUT/multigpu/one.log" "$what")
    all=$(seconds "$OUT/multigpu/all.log" "$what")
    case $what in
      stepping) label="stepping (the advance calls; the slowest GPU's)" ;;
      recording) label="stepping and recording" ;;
      command) label="whole command" ;;
    esac
    record "| $label | $one | $all | $(awk -v a="$one" -v b="$all" 'BEGIN { if (b > 0) printf "%.2fx", a / b; else print "n/a" }') |"
  done
  record ""
  record "goal (issue 27 item 6): >= 1.8x one GPU on two"
}

# The median of the numbers on stdin.
median() { sort -g | awk '{ v[NR] = $1 } END { if (NR == 0) print "nan"; else if (NR % 2) print v[(NR + 1) / 2]; else print (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

# fmpc_sim_bench's rows of a CSV as "key us_per_step" lines (key: model..scenes, spaces as _).
bench_rows() { awk -F, 'NR > 1 && $17 ~ /ok/ { key = $1 "/" $2 "/" $4 "/" $5 "/" $6 "/" $7 "/" $8; gsub(/ /, "_", key); print key, $14 }' "$1"; }

# This tree against the baseline commit (see the header): both fmpc_sim_bench binaries and both fmpc, alternately.
baseline_section() {
  local commit
  commit=$(cat "$CARRY/baseline-commit.txt" 2>/dev/null)
  section "baseline: this tree against ${commit:-?} on the same GPU, alternately"
  if [[ ! -f "$CARRY/baseline-src.tar.xz" ]] || ! unpack_programs || [[ ! -x "$UNPACKED/bin/fmpc-baseline" ]]; then
    fail "no baseline carried: run 'BASELINE=<commit> BASELINE_FMPC=... FMPC=... bash bench/run_gpu.sh --prepare'"
    return 1
  fi
  local base="$BUILD/baseline" current="$BUILD/bench/sim/fmpc_sim_bench"
  [[ -x "$current" ]] || { fail "no $current (the build section builds it)"; return 1; }
  # A baseline fmpc_sim_bench built on the build machine (BASELINE_SIM_BENCH at --prepare) spares this machine its build.
  if [[ -x "$UNPACKED/bin/fmpc_sim_bench-baseline" && ! -x "$base/build/bench/sim/fmpc_sim_bench" ]]; then
    rm -rf "$base" && mkdir -p "$base" && tar -C "$base" -xJf "$CARRY/baseline-src.tar.xz" ||
      { fail "unpack baseline"; return 1; }
    place_program fmpc_sim_bench-baseline "$base/build/bench/sim/fmpc_sim_bench"
  fi
  if [[ ! -x "$base/build/bench/sim/fmpc_sim_bench" ]]; then
    rm -rf "$base" && mkdir -p "$base" && tar -C "$base" -xJf "$CARRY/baseline-src.tar.xz" || { fail "unpack baseline"; return 1; }
    local generator=()
    command -v ninja > /dev/null && generator=(-G Ninja)
    if ! (export PATH="/usr/local/cuda/bin:$PATH"
          cmake -S "$base/baseline-src" -B "$base/build" ${generator[@]+"${generator[@]}"} -DFMPC_GPU_ONLY=ON \
            -DFMPC_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 -DCMAKE_BUILD_TYPE=Release -DFMPC_EIGEN_INCLUDE_DIR="$CARRY/eigen3" &&
          cmake --build "$base/build" --target fmpc_sim_bench -j "$JOBS") > "$OUT/baseline_build.log" 2>&1; then
      tail -20 "$OUT/baseline_build.log"
      fail "baseline fmpc_sim_bench build (see baseline_build.log)"
      return 1
    fi
  fi
  local rows="${BASELINE_ROWS:-small,cohort,fem,large}" repeats="${BASELINE_REPEATS:-3}" r tree row
  local results="$OUT/baseline_runs.txt"
  : > "$results"
  mkdir -p "$OUT/baseline" "$BUILD/scenes"
  for ((r = 1; r <= repeats; ++r)); do
    for row in ${rows//,/ }; do
      for tree in this baseline; do
        local bench="$current" fmpc="$UNPACKED/bin/fmpc" source="$ROOT" args=()
        if [[ $tree == baseline ]]; then
          bench="$base/build/bench/sim/fmpc_sim_bench" fmpc="$UNPACKED/bin/fmpc-baseline" source="$base/baseline-src"
        fi
        case $row in
          small)
            "$fmpc" simulate "$source/bench/scenes/small_box_springs.yaml" --backend cuda -o "$BUILD/scenes/baseline_$tree" \
              > "$OUT/baseline/small_${tree}_$r.log" 2>&1 || { fail "small box on $tree (baseline/small_${tree}_$r.log)"; continue; }
            echo "$tree small_box_springs_end_to_end_steps_per_s $(json_field "$BUILD/scenes/baseline_$tree/summary.json" steps_per_second)" >> "$results"
            continue ;;
          large) args=(--spring-cells 240) ;;
          fem) args=(--fem-only --fem-cells 120) ;;
          cohort) args=(--cohort-only --cohort 1000) ;;
          *) fail "BASELINE_ROWS: unknown row '$row' (small, large, fem, cohort)"; continue ;;
        esac
        mkdir -p "$OUT/baseline/${row}_${tree}_$r"
        if "$bench" "${args[@]}" --out "$OUT/baseline/${row}_${tree}_$r" > "$OUT/baseline/${row}_${tree}_$r.log" 2>&1; then
          bench_rows "$OUT/baseline/${row}_${tree}_$r/sim_bench.csv" | sed "s/^/$tree /" >> "$results"
        else
          fail "fmpc_sim_bench ${args[*]} on $tree (baseline/${row}_${tree}_$r.log)"
        fi
      done
    done
  done
  {
    echo "| row | this: median (runs) | ${commit:-baseline}: median (runs) | this / baseline |"
    echo "| --- | --- | --- | --- |"
    local key
    for key in $(awk '{ print $2 }' "$results" | awk '!seen[$0]++'); do
      local mine theirs
      mine=$(awk -v k="$key" '$1 == "this" && $2 == k { print $3 }' "$results" | median)
      theirs=$(awk -v k="$key" '$1 == "baseline" && $2 == k { print $3 }' "$results" | median)
      echo "| $key | $mine ($(awk -v k="$key" '$1 == "this" && $2 == k { printf "%s ", $3 }' "$results")) | $theirs ($(awk -v k="$key" '$1 == "baseline" && $2 == k { printf "%s ", $3 }' "$results")) | $(awk -v a="$mine" -v b="$theirs" 'BEGIN { if (b > 0) printf "%.4f", a / b; else print "-" }') |"
    done
  } > "$OUT/baseline.md"
  record "us per step for fmpc_sim_bench rows (lower is better), steps/s for the end-to-end row (higher is better):"
  cat "$OUT/baseline.md" | tee -a "$SUMMARY"
}

# build-gpu-carry/programs.tar.xz (bundle_program) unpacked once into $UNPACKED.
unpack_programs() {
  [[ -f "$CARRY/programs.tar.xz" ]] || return 1
  if [[ ! -d "$UNPACKED" || "$CARRY/programs.tar.xz" -nt "$UNPACKED" ]]; then
    rm -rf "$UNPACKED" && mkdir -p "$BUILD" && tar -C "$BUILD" -xJf "$CARRY/programs.tar.xz" || return 1
    touch "$UNPACKED"
  fi
}

# need_program NAME: the carried programs unpacked with NAME among them; otherwise the section fails saying how to
# carry it.
need_program() {
  unpack_programs && [[ -x "$UNPACKED/bin/$1" ]] && return 0
  fail "no $1 in $CARRY/programs.tar.xz: build it in a CUDA build and run 'FMPC=<CUDA build>/tools/fmpc bash bench/run_gpu.sh --prepare' on the build machine"
  return 1
}

# sofa_liver_file NAME: the path the scenes name for SOFA's liver files, ../shared/data/sofa-liver/NAME beside the
# repository, put there from the carry (--prepare carries liver.msh and liver-smooth.obj) when this machine has none.
sofa_liver_file() {
  local path="$ROOT/../shared/data/sofa-liver/$1"
  if [[ ! -f "$path" && -f "$CARRY/sofa-liver/$1" ]]; then
    mkdir -p "$(dirname "$path")" && cp "$CARRY/sofa-liver/$1" "$path"
  fi
  echo "$path"
}

# Host setup of large boxes on this machine's cores (bench/setup; docs/performance.md "Host setup and frames").
# Issue 26 item 7: each law on each element kind at 120^3 cells (10,368,000 elements), float and double,
# semi-implicit Euler, GPU only; LAW_ELEMENTS (law:element pairs, the scene keywords) picks them.
laws_section() {
  section "laws: element-steps/s per law and element kind (fmpc_sim_bench --fem-only --fem-cells 120)"
  local bench="$BUILD/bench/sim/fmpc_sim_bench" pair
  [[ -x "$bench" ]] || { fail "no $bench (the build section builds it)"; return 1; }
  for pair in ${LAW_ELEMENTS:-corotational:linear stable_neo_hookean:linear corotational:quadratic stable_neo_hookean:quadratic}; do
    local law=${pair%%:*} element=${pair##*:}
    mkdir -p "$OUT/laws/$law-$element"
    if "$bench" --fem-only --fem-cells "${LAW_CELLS:-120}" --fem-law "$law" --fem-element "$element" \
        --out "$OUT/laws/$law-$element" > "$OUT/laws/$law-$element.log" 2>&1; then
      record "$law on $element elements:"
      grep -E '^\| .*cuda' "$OUT/laws/$law-$element/sim_bench.md" | tee -a "$SUMMARY"
    else
      tail -5 "$OUT/laws/$law-$element.log"
      fail "laws: $law on $element (see laws/$law-$element.log)"
    fi
  done
}

setup_section() {
  section "setup: fmpc_setup_bench (host setup, peak bytes per spring)"
  local bench="$BUILD/bench/setup/fmpc_setup_bench"
  [[ -x "$bench" ]] || { fail "no $bench (the build section builds it)"; return 1; }
  if "$bench" --cells "${SETUP_CELLS:-60,120,240}" --breakdown --simulator --out "$OUT" > "$OUT/setup_bench.log" 2>&1 &&
      "$bench" --cells 120 --threads 1 > "$OUT/setup_bench_1thread.log" 2>&1; then
    record "setup_bench: ok (setup_bench.log, setup_bench_1thread.log)"
  else
    tail -5 "$OUT/setup_bench.log" "$OUT/setup_bench_1thread.log"
    fail "setup_bench (see setup_bench*.log)"
  fi
}

# ncu on the kernels behind issue 10's and 13's goals. Sections: throughput, memory, occupancy, warp states.
profile_section() {
  section "profile: Nsight Compute"
  local ncu
  ncu=$(command -v ncu || ls /usr/local/cuda/bin/ncu 2>/dev/null | head -1)
  [[ -n "$ncu" ]] || { fail "ncu not found"; return 1; }
  local sections=(--section SpeedOfLight --section MemoryWorkloadAnalysis --section Occupancy --section LaunchStats
    --section WarpStateStats --section SchedulerStats --section ComputeWorkloadAnalysis)
  "$ncu" "${sections[@]}" --kernel-name regex:'element_forces|fused_step' --launch-skip 8 --launch-count 4 \
    "$BUILD/bench/sim/fmpc_sim_bench" --fem-only --fem-cells 120 --min-seconds 0.02 > "$OUT/profile_fem.txt" 2>&1 ||
    fail "ncu on the FEM bench (see profile_fem.txt)"
  if unpack_programs && [[ -x "$UNPACKED/bin/fmpc" ]]; then
    mkdir -p "$BUILD/scenes"
    "$ncu" "${sections[@]}" --kernel-name regex:'fused_step' --launch-skip 4 --launch-count 2 \
      "$UNPACKED/bin/fmpc" simulate "$ROOT/bench/scenes/large_box_springs.yaml" --backend cuda --steps 20 \
      -o "$BUILD/scenes/profile_large" > "$OUT/profile_large_springs.txt" 2>&1 ||
      fail "ncu on large_box_springs (see profile_large_springs.txt)"
    "$ncu" "${sections[@]}" --kernel-name regex:'persistent|fused_step' --launch-skip 4 --launch-count 2 \
      "$UNPACKED/bin/fmpc" simulate "$ROOT/bench/scenes/small_box_springs.yaml" --backend cuda --steps 3000 \
      -o "$BUILD/scenes/profile_small" > "$OUT/profile_small_springs.txt" 2>&1 ||
      fail "ncu on small_box_springs (see profile_small_springs.txt)"
    # Implicit Euler's conjugate gradient (docs/performance.md, seventeenth to nineteenth runs): the 20^3 box's
    # per-iteration kernels (the element products and the fused stages) and every kernel's duration over 400
    # launches, and SOFA's liver at SOFA's cap of 25 iterations (its mesh from the carry): the one-block solve's
    # sections and stall reasons, and every kernel's duration over 60 launches of a run.
    "$ncu" "${sections[@]}" --kernel-name regex:'cg_fused_stage_kernel|implicit_element_apply_kernel' \
      --launch-skip 20 --launch-count 3 "$UNPACKED/bin/fmpc" simulate "$ROOT/bench/scenes/box20_fem_implicit.yaml" \
      --backend cuda --steps 40 -o "$BUILD/scenes/profile_box20" > "$OUT/profile_implicit_box20.txt" 2>&1 ||
      fail "ncu on box20_fem_implicit (see profile_implicit_box20.txt)"
    "$ncu" --metrics gpu__time_duration.sum --launch-skip 400 --launch-count 400 \
      "$UNPACKED/bin/fmpc" simulate "$ROOT/bench/scenes/box20_fem_implicit.yaml" --backend cuda --steps 30 \
      -o "$BUILD/scenes/profile_box20_durations" > "$OUT/profile_implicit_box20_durations.txt" 2>&1 ||
      fail "ncu durations on box20_fem_implicit (see profile_implicit_box20_durations.txt)"
    if [[ -f "$CARRY/sofa-liver/liver.msh" ]]; then
      sed -e "s#file: .*liver.msh#file: $CARRY/sofa-liver/liver.msh#" \
        -e 's#^precision: double#precision: double\nsolver: {method: cg, max_iterations: 25}#' \
        "$ROOT/rulesets/scenes/sofa_liver_fem.yaml" > "$BUILD/scenes/sofa_liver_cap25.yaml"
      "$ncu" "${sections[@]}" --kernel-name regex:'cg_block_kernel|cg_persistent' --launch-skip 20 --launch-count 1 \
        --metrics 'regex:smsp__average_warps_issue_stalled_.*_per_issue_active\.ratio,smsp__inst_executed.sum' \
        "$UNPACKED/bin/fmpc" simulate "$BUILD/scenes/sofa_liver_cap25.yaml" --backend cuda --steps 60 \
        -o "$BUILD/scenes/profile_liver" > "$OUT/profile_implicit_liver.txt" 2>&1 ||
        fail "ncu on SOFA's liver, CG capped at 25 (see profile_implicit_liver.txt)"
      "$ncu" --metrics gpu__time_duration.sum --launch-skip 60 --launch-count 60 \
        "$UNPACKED/bin/fmpc" simulate "$BUILD/scenes/sofa_liver_cap25.yaml" --backend cuda --steps 120 \
        -o "$BUILD/scenes/profile_liver_durations" > "$OUT/profile_implicit_liver_durations.txt" 2>&1 ||
        fail "ncu durations on SOFA's liver (see profile_implicit_liver_durations.txt)"
    fi
  fi
  record "profile: $(ls "$OUT"/profile_*.txt 2>/dev/null | wc -l) reports"
}

# Long fuzzing runs of the carried libFuzzer targets (tests/fuzz/run_fuzzers.sh), FUZZ_SECONDS (default 540) with
# FUZZ_JOBS processes per target (default: the machine's cores over the targets); the corpora stay in
# $BUILD/fuzz-corpus, so runs on a warm machine add up (the CPU seconds per target, over all runs, in the report).
fuzz_section() {
  section "fuzz: libFuzzer targets (ASan+UBSan, built on the build machine)"
  if ! unpack_programs || ! ls "$UNPACKED"/bin/fuzz_* > /dev/null 2>&1; then
    fail "no fuzz targets in $CARRY/programs.tar.xz: build build-asan (tools/run sanitize) and run --prepare"
    return 1
  fi
  # An earlier run's corpora and CPU-second totals (its $OUT/fuzz-corpus.tar.xz, put into build-gpu-carry by
  # --prepare with FUZZ_CORPUS=...): this run goes on from them.
  if [[ -f "$CARRY/fuzz-corpus.tar.xz" && ! -d "$BUILD/fuzz-corpus" ]]; then
    mkdir -p "$BUILD" && tar -C "$BUILD" -xJf "$CARRY/fuzz-corpus.tar.xz" || fail "unpacking the carried fuzz corpus"
  fi
  # The targets carried (run_fuzzers.sh's own default list names targets a sanitizer build may lack: the Python
  # module's, without -DFMPC_PYTHON=ON).
  # FUZZ_TARGETS (space-separated names, e.g. "fll fcl python_arguments") narrows them, so that a call's cores go to
  # the targets that still need CPU time.
  local program name targets=()
  for program in "$UNPACKED"/bin/fuzz_*; do
    name=${program##*/fuzz_}
    [[ -z "${FUZZ_TARGETS:-}" || " $FUZZ_TARGETS " == *" $name "* ]] || continue
    # The Python module's target embeds the build machine's CPython, which aborts at start without its standard
    # library (seen on the GPU machine: "failed to get the Python codec of the filesystem encoding").
    if [[ $name == python_arguments && ! -d /usr/lib/python3.11/encodings ]]; then
      record "fuzz_python_arguments: skipped (no /usr/lib/python3.11 here; run it on the build machine: \
tests/fuzz/run_fuzzers.sh build-asan SECONDS python_arguments)"
      continue
    fi
    targets+=("$name")
  done
  [[ ${#targets[@]} -gt 0 ]] || { fail "FUZZ_TARGETS='${FUZZ_TARGETS:-}' names no carried target"; return 1; }
  local jobs=${FUZZ_JOBS:-$(( JOBS / ${#targets[@]} > 0 ? JOBS / ${#targets[@]} : 1 ))}
  FMPC_FUZZ_BINARIES="$UNPACKED/bin" FMPC_FUZZ_SEEDS="$UNPACKED/seeds" \
    bash "$ROOT/tests/fuzz/run_fuzzers.sh" --jobs "$jobs" "$BUILD" "${FUZZ_SECONDS:-540}" "${targets[@]}" \
    > "$OUT/fuzz.log" 2>&1
  local status=$?
  grep -E '^fuzz_|^finding' "$OUT/fuzz.log" | tee -a "$SUMMARY"
  mkdir -p "$OUT/fuzz"
  cp "$BUILD"/fuzz-corpus/*.0.log "$OUT/fuzz/" 2>/dev/null
  local findings
  findings=$(find "$BUILD/fuzz-corpus" -path '*-findings/*' -type f 2>/dev/null)
  if [[ -n "$findings" ]]; then
    mkdir -p "$OUT/fuzz/findings" && cp $findings "$OUT/fuzz/findings/"
  fi
  tar -C "$BUILD" -cJf "$OUT/fuzz-corpus.tar.xz" --exclude='*.log' --exclude='*-seeds' fuzz-corpus ||
    fail "packing the fuzz corpus"
  [[ $status -eq 0 ]] || fail "fuzzing (exit $status; see fuzz.log and fuzz/findings)"
}

# The generated CUDA evaluator and table lookups (bench/gpu/evaluator_gpu_bench.cu): built with nvcc alone, so
# it needs only the headers `--prepare` generated, not the CMake build above.
evaluator_section() {
  section "evaluator: generated CUDA evaluator and table lookups (bench/gpu)"
  local dir="$CARRY/evaluator"
  if [[ ! -f "$dir/liver_evaluator.cuh" || ! -f "$dir/liver_it2_evaluator.cuh" || ! -f "$dir/liver_table2.h" ||
        ! -f "$dir/liver_table2f.h" ||
        ! -f "$dir/liver_table5.h" || ! -f "$dir/liver_table5f.h" || ! -f "$dir/liver_table5r7.h" ||
        ! -f "$dir/liver_table5r5.h" ]] || ! grep -q kPackedValues "$dir/liver_table5.h"; then
    fail "no (or outdated) generated headers in $dir: run 'bash bench/run_gpu.sh --prepare' on the build machine (after building fmpc)"
    return 1
  fi
  local binary="$BUILD/evaluator_gpu_bench"
  mkdir -p "$BUILD"
  if ! /usr/local/cuda/bin/nvcc -std=c++17 -O3 -arch=sm_90 --Werror all-warnings -Xptxas -v -I"$ROOT" -I"$dir" \
      "$ROOT/bench/gpu/evaluator_gpu_bench.cu" -o "$binary" > "$OUT/evaluator_build.log" 2>&1; then
    grep -E 'error' "$OUT/evaluator_build.log" | head -20
    fail "nvcc bench/gpu/evaluator_gpu_bench.cu (see evaluator_build.log)"
    return 1
  fi
  local points=$((1 << 24))
  [[ $QUICK -eq 1 ]] && points=$((1 << 22))
  "$binary" "$OUT" "$points" > "$OUT/evaluator_gpu.log" 2>&1
  local status=$?
  [[ -f "$OUT/evaluator_gpu.md" ]] && cat "$OUT/evaluator_gpu.md" >> "$SUMMARY"
  case $status in
    0) record "evaluator_gpu_bench: ok (evaluator_gpu.csv, evaluator_gpu.md)" ;;
    1) fail "evaluator_gpu_bench: a GPU result disagrees with the CPU (see evaluator_gpu.md)" ;;
    *) tail -5 "$OUT/evaluator_gpu.log"; fail "evaluator_gpu_bench: exit $status (see evaluator_gpu.log)" ;;
  esac
  # The evaluator, pack and lookup kernels (both layouts) under compute-sanitizer, on a small batch.
  if [[ $SKIP_SANITIZERS -eq 0 ]]; then
    local sanitizer tool
    sanitizer=$(command -v compute-sanitizer || ls /usr/local/cuda/bin/compute-sanitizer \
      /usr/local/cuda/compute-sanitizer/compute-sanitizer 2>/dev/null | head -1)
    mkdir -p "$BUILD/sanitized_bench"
    for tool in memcheck racecheck; do
      "$sanitizer" --tool "$tool" --error-exitcode 99 "$binary" "$BUILD/sanitized_bench" 65536 \
        > "$OUT/evaluator_sanitizer_$tool.log" 2>&1
      local rc=$?
      local errors
      errors=$(grep -E 'ERROR SUMMARY|RACECHECK SUMMARY' "$OUT/evaluator_sanitizer_$tool.log" | tail -1)
      if [[ $rc -eq 0 ]]; then record "evaluator bench under $tool: ok (${errors:-no summary line})"
      else fail "evaluator bench under $tool: exit $rc (${errors:-see evaluator_sanitizer_$tool.log})"; fi
    done
  fi
}

device_info
if wanted tests || wanted sanitizers || wanted bench || wanted laws || wanted setup || wanted profile || wanted baseline; then
  if build_section; then
    simulator_section
    wanted laws && laws_section
    wanted setup && setup_section
    wanted profile && profile_section
    wanted baseline && baseline_section
  fi
fi
wanted scenes && scenes_section
wanted haptic && haptic_section
wanted press && press_section
wanted multigpu && multigpu_section
wanted evaluator && evaluator_section
wanted fuzz && fuzz_section

echo
echo "================ summary ($OUT/summary.md)"
cat "$SUMMARY"
if [[ -f "$OUT/sim_bench.md" ]]; then
  echo
  echo "## simulator benchmark (us per step; spring-steps/s = springs x steps / s)"
  echo
  cat "$OUT/sim_bench.md"
fi
if [[ -f "$OUT/evaluator_gpu.md" ]]; then
  echo
  echo "## generated evaluator and table lookups (per second; checked against the CPU)"
  echo
  cat "$OUT/evaluator_gpu.md"
fi
exit $FAILED
