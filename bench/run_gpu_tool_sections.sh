# The sections of bench/run_gpu.sh that press a rigid tool into tissue: haptic (issue 27 item 4) and press (issue 28
# item 3). Sourced by run_gpu.sh, whose helpers (section, record, fail, need_program, sofa_liver_file) and variables
# (ROOT, CARRY, OUT, UNPACKED, SUMMARY, QUICK) they use; run_gpu.sh's header says what each section measures.

# The haptic loop (issue 27 item 4): fmpc_haptic_bench, built on the build machine with CUDA and carried, on CUDA and
# on this machine's CPU, both modes each; the goal is p99 <= 1 ms on an H100.
haptic_section() {
  section "haptic: 1 kHz loop through fmpc::runtime's Session (bench/haptic)"
  need_program fmpc_haptic_bench || return 1
  local seconds="${HAPTIC_SECONDS:-30}" backend
  [[ $QUICK -eq 1 ]] && seconds=5
  mkdir -p "$OUT/haptic"
  : > "$OUT/haptic.md"
  local surface
  surface=$(sofa_liver_file liver-smooth.obj)
  # Each tick reports its mean force (one step and one reading at a time); on CUDA the block's explicit mode also runs
  # as one call per tick with the tick-end force only (--force end: the loop's latency without the readings) and with
  # contact damping (--contact-damping 1: the chatter of the undamped contact gone).
  local tissue run extra
  for tissue in block liver; do
    if [[ $tissue == liver && ! -f "$surface" ]]; then
      fail "no $surface (nor in $CARRY/sofa-liver): the haptic loop on the liver did not run"
      continue
    fi
    local runs=(cuda cpu)
    [[ $tissue == block ]] && runs+=(cuda_end cuda_damped)
    for run in "${runs[@]}"; do
      backend=${run%%_*}
      case "$run" in
        cuda_end) extra=(--modes explicit --force end) ;;
        cuda_damped) extra=(--modes explicit --contact-damping 1) ;;
        *) extra=() ;;
      esac
      mkdir -p "$OUT/haptic/$tissue/$run"
      if "$UNPACKED/bin/fmpc_haptic_bench" --backend "$backend" --seconds "$seconds" --tissue "$tissue" \
          --liver-scene "$ROOT/rulesets/scenes/liver_meshed.yaml" ${extra[@]+"${extra[@]}"} \
          --out "$OUT/haptic/$tissue/$run" > "$OUT/haptic/$tissue/$run.log" 2>&1; then
        grep -E '^(implicit|explicit) on |^  force change' "$OUT/haptic/$tissue/$run.log" | sed "s/^/$tissue $run: /" |
          tee -a "$SUMMARY"
        grep -E '^\|' "$OUT/haptic/$tissue/$run.log" | awk -v first="$([[ -s "$OUT/haptic.md" ]] && echo 0 || echo 1)" \
          -v tissue="$tissue $run" 'NR <= 2 { if (first == 1) print (NR == 1 ? "| tissue, run " : "| --- ") $0; next }
                                    { print "| " tissue " " $0 }' >> "$OUT/haptic.md"
      else
        tail -5 "$OUT/haptic/$tissue/$run.log"
        fail "fmpc_haptic_bench --backend $backend --tissue $tissue ${extra[*]} (see haptic/$tissue/$run.log)"
      fi
    done
  done
  cat "$OUT/haptic.md" >> "$SUMMARY"
}

# The liver pressed by the sphere (issue 28 item 3; docs/trade.md, "The surface split under the tool"): the carried
# fmpc_graded_press_bench on bench/scenes/liver_sphere_press.yaml, quadratic tetrahedra, the surface split to the size
# field, pressed on CUDA. PRESS_ROWS picks the meshes: gH is H near and 0.72 far within 1.2 units of the sphere's
# centre (gH@D within D units), uH is H everywhere (default: the table's rows); PRESS_ARGS adds the bench's arguments
# to every row (e.g. stiffness_ratio=64), PRESS_SCENE another scene of the repository (bench/scenes/liver_tip_press.yaml:
# a 5 mm tip). Each row is cut off after PRESS_TIMEOUT seconds (default 600) and runs
# alone, so that its wall time is the press's own.
press_section() {
  section "press: the liver pressed by the sphere, graded and uniform (bench/graded)"
  need_program fmpc_graded_press_bench || return 1
  local surface
  surface=$(sofa_liver_file liver-smooth.obj)
  [[ -f "$surface" ]] || { fail "no $surface (nor in $CARRY/sofa-liver): the press did not run"; return 1; }
  mkdir -p "$OUT/press"
  local row size distance sizes status log scene="$ROOT/${PRESS_SCENE:-bench/scenes/liver_sphere_press.yaml}"
  for row in ${PRESS_ROWS:-g0.12 g0.09 g0.06 g0.045 g0.035 g0.03 u0.36 u0.27 u0.2 u0.16}; do
    size=${row#?}
    distance=1.2
    [[ $size == *@* ]] && distance=${size#*@} && size=${size%@*}
    case "$row" in
      g*) sizes=(size_near="$size" size_far=0.72 near_distance="$distance") ;;
      u*) sizes=(size_near="$size" size_far="$size") ;;
      *) fail "PRESS_ROWS: '$row' is neither gSIZE nor uSIZE"; continue ;;
    esac
    # The device tool brings back no file whose name holds an '@'.
    log="$OUT/press/${row//@/_at_}.log"
    timeout "${PRESS_TIMEOUT:-600}" "$UNPACKED/bin/fmpc_graded_press_bench" "$scene" \
      solver=cg lowering=2 tolerance=1e-4 "${sizes[@]}" element=quadratic split_surface=1 backend=cuda label="$row" \
      ${PRESS_ARGS:-} \
      > "$log" 2>&1
    status=$?
    case $status in
      0) record "press $(tail -1 "$log")" ;;
      1) record "press $(tail -1 "$log") (not settled within the bench's steps)" ;;
      124) record "press $row: cut off after ${PRESS_TIMEOUT:-600} s" ;;
      *) tail -5 "$log"; fail "press $row (see press/${log##*/})" ;;
    esac
  done
}
