#!/usr/bin/env bash
# Regenerates docs/results.md and docs/figures/*.png from scratch: the paper's
# evaluation (section 4) applied to every dataset the project can run.
#
#   scripts/reproduce.sh [--quick] [--check]
#
#   (no option) full run (<= 60 min on a 2-core machine): simulated drives of
#               300-1000 frames, the real KITTI data of tests/data and the real
#               data given below; writes docs/results.md, docs/figures/*.png
#               and the results block of README.md.
#   --quick     small drives (< 3 min); writes docs/results_quick.md, the part
#               of the results that does not depend on the machine (no frame
#               times), and its figures under $OUT/figures only.
#   --check     with --quick: write nothing under docs/, compare the fresh
#               table with docs/results_quick.md and exit 1 when they differ
#               (the CTest entry script_reproduce_quick).
#
# Real data beyond tests/data, each optional (full run only):
#   KITTI_RAW=DIR        a folder of KITTI raw scans as PCD, e.g. the 22-frame
#                        snippet /work/shared/data/kitti_raw/snippet_22 (no
#                        ground truth: path length and frame time only)
#   KITTI_RAW_DRIVE=DIR  a KITTI raw drive as published (..._drive_NNNN_sync,
#                        with velodyne_points/ and oxts/); KITTI_RAW_CALIB=DIR
#                        its day's calib folder (default: DIR/../calib_<date>).
#                        The OXTS trajectory is the reference
#                        (scripts/kitti_raw_drive.py); runs deskew the sweeps.
#   KITTI_ROOT=DIR       a KITTI odometry sequence dataset/sequences/NN
#                        (velodyne/, calib.txt, times.txt; ground truth as
#                        semlio_kitti finds it); KITTI_FRAMES=N caps its length.
#   BALM_OS0=DIR         the BALM hand-held OS0-class keyframes (velodyne/,
#                        poses.txt, times.txt), read by semlio_run with the
#                        detected beam table and the hand-held motion profile
#                        (sensor: {profile: auto, platform: hand_held}); their
#                        reference poses are BALM's odometry, not ground truth.
#   BAGS="FILE ..."      your recordings (ROS 1 bag, MCAP, rosbag2 .db3), read by
#                        semlio_run with its sensor detection (no reference:
#                        path length and frame time only). Both runs, quick and
#                        full, also read the three KITTI scans of tests/data/bags
#                        from a ROS 1 bag and an MCAP file.
# Environment: BUILD_DIR (build), OUT (results/reproduce[_quick]), SKIP_BUILD=1
# (use BUILD_DIR as built, install nothing), SEED (1), LONG_FRAMES (1000: the
# long simulated drive of the full run), DATASETS (shell patterns: run only the
# datasets whose names match, e.g. 'sim_urban_heavy sim_rural kitti*').
#
# Each dataset runs semlio_kitti (a recording: semlio_run) six times (configurations below, all with
# the same settings otherwise) one after the other; accuracy is
# deterministic (same binary, same numbers), frame times are not.
set -euo pipefail
cd "$(dirname "$0")/.."

QUICK=0
CHECK=0
for arg in "$@"; do
  case "$arg" in
    --quick) QUICK=1 ;;
    --check) CHECK=1 ;;
    -h|--help) sed -n '2,36p' "$0"; exit 0 ;;
    *) echo "reproduce.sh: unknown option '$arg' (see --help)" >&2; exit 2 ;;
  esac
done
if [[ $CHECK == 1 && $QUICK == 0 ]]; then
  echo "reproduce.sh: --check compares the --quick table; use --quick --check" >&2
  exit 2
fi

BUILD_DIR=${BUILD_DIR:-build}
SEED=${SEED:-1}
if [[ $QUICK == 1 ]]; then OUT=${OUT:-results/reproduce_quick}; else OUT=${OUT:-results/reproduce}; fi
if [[ -z "${SKIP_BUILD:-}" ]]; then
  scripts/install_deps.sh python3-matplotlib
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_simulate semlio_kitti semlio_convert semlio_segment_eval \
    semlio_run
fi
BIN="$BUILD_DIR/examples"
for tool in semlio_simulate semlio_kitti semlio_convert semlio_segment_eval; do
  [[ -x "$BIN/$tool" ]] || { echo "reproduce.sh: $BIN/$tool not built" >&2; exit 1; }
done
PLOTS=1
/usr/bin/python3 -c "import matplotlib" 2> /dev/null || PLOTS=0
if [[ $PLOTS == 0 && $QUICK == 0 ]]; then
  echo "reproduce.sh: python3-matplotlib is missing (the full run draws the figures)" >&2
  exit 1
fi

rm -rf "$OUT"
mkdir -p "$OUT/data" "$OUT/runs" "$OUT/configs"
start=$(date +%s)
# The machine's load, for reading the frame times (load.txt: start and end).
load_now() { echo "$(cut -d' ' -f1-3 /proc/loadavg 2> /dev/null) on $(nproc) cores"; }
echo "start: $(load_now)" > "$OUT/load.txt"

# --- the six configurations of Table 3 --------------------------------------
# semlio_kitti has two presets; the parts of `full` are switched off through
# its --config YAML (examples/kitti/settings_yaml.hpp), every run with the
# dataset's labels:
# - semantic keyframes off: semantic_keyframes.weight_min = 1 clamps W_se to
#   1 (eq. 20), so tau' = tau (eq. 21-22): the pose-threshold rule with the
#   baseline's thresholds (both 1.0 m / 0.2 rad);
# - semantic weights off: semantic_weights.mode = off (every weight of eq.
#   10-12 is 1);
# - normal-consistency association off: normal.candidates = keep = 5 and
#   max_angle_rad = 1.57 (the largest the validator allows is pi/2) keep the 5
#   nearest map points within 1 m, as NearestK does (nearly: a candidate
#   whose axis is exactly perpendicular to the scan's would still be dropped).
nearest5='normal: {candidates: 5, keep: 5, max_angle_rad: 1.57}'
cat > "$OUT/configs/full.yaml" <<< "{}"
cat > "$OUT/configs/baseline.yaml" <<< "{}"
cat > "$OUT/configs/full_pose_kf.yaml" <<< "semantic_keyframes: {weight_min: 1.0}"
printf "semantic_weights: {mode: 'off'}\nsemantic_keyframes: {weight_min: 1.0}\n" > "$OUT/configs/nc_only.yaml"
printf '%s\nsemantic_keyframes: {weight_min: 1.0}\n' "$nearest5" > "$OUT/configs/weights_only.yaml"
printf "%s\nsemantic_weights: {mode: 'off'}\n" "$nearest5" > "$OUT/configs/keyframes_only.yaml"
# name preset
CONFIGS=("baseline baseline" "full full" "nc_only full" "weights_only full" "keyframes_only full"
         "full_pose_kf full")

# --- datasets ----------------------------------------------------------------
# datasets.tsv: name, dir, kind (simulated|real), scene, label source, extra
# YAML (deskew for raw sweeps; "-" none), reference
DS="$OUT/datasets.tsv"
: > "$DS"
# DATASETS="PATTERN ...": run only the datasets whose names match one of the
# shell patterns (e.g. DATASETS='sim_urban_heavy kitti*'); default: all.
wanted() {
  [[ -z "${DATASETS:-}" ]] && return 0
  local p
  for p in $DATASETS; do
    # shellcheck disable=SC2053  # a pattern on purpose
    [[ "$1" == $p ]] && return 0
  done
  return 1
}
simulate() {  # name world traffic frames
  wanted "$1" || return 0
  echo "== simulating $1: $2, $3 traffic, $4 frames, seed $SEED"
  "$BIN/semlio_simulate" --world "$2" --traffic "$3" --frames "$4" --seed "$SEED" --threads 2 \
    --out "$OUT/data/$1" > /dev/null
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$1" "$OUT/data/$1" simulated "$2, $3 traffic" predictions - \
    "simulator (exact)" >> "$DS"
}
pcd_folder() {  # name dir: a folder of PCD scans -> a KITTI layout (no ground truth)
  wanted "$1" || return 0
  mkdir -p "$OUT/data/$1/velodyne"
  local i=0 f
  for f in "$2"/*.pcd; do
    "$BIN/semlio_convert" "$f" "$(printf '%s/data/%s/velodyne/%06d.bin' "$OUT" "$1" "$i")" > /dev/null
    i=$((i + 1))
  done
  printf 'deskew: {mode: constant_velocity, point_times: azimuth}\n' > "$OUT/configs/$1.extra.yaml"
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$1" "$OUT/data/$1" real "KITTI raw HDL-64E, urban road" geometric \
    "$OUT/configs/$1.extra.yaml" "none" >> "$DS"
}
recording() {  # name file scene [semlio_run option ...]: a ROS 1 bag / MCAP / rosbag2 of real scans
  wanted "$1" || return 0
  printf '%s\n' "${@:4}" > "$OUT/configs/$1.args"
  printf 'deskew: {mode: constant_velocity, point_times: azimuth}\n' > "$OUT/configs/$1.extra.yaml"
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$1" "$2" real "$3" geometric "$OUT/configs/$1.extra.yaml" "none" >> "$DS"
}
if [[ $QUICK == 1 ]]; then
  simulate sim_urban_heavy urban heavy 30
  simulate sim_rural rural light 20
else
  # sim_urban_heavy is scripts/demo.sh's drive (same world, traffic, length,
  # seed and labels), so its row is what the demo prints.
  simulate sim_urban_heavy urban heavy 300
  simulate sim_urban_long urban heavy "${LONG_FRAMES:-1000}"
  simulate sim_rural rural light 300
  simulate sim_highway highway light 300
fi
wanted kitti00_2 && printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' kitti00_2 tests/data/kitti/sequences/00 real "KITTI 00 (first 2 scans), urban" \
  geometric - "KITTI ground truth" >> "$DS"
pcd_folder kitti_raw_3 tests/data/kitti_raw/snippet_22
# The same three scans as recorded by the ROS reference implementations
# (tests/data/bags/README.md), read without ROS and told what a KITTI user
# knows (the sensor, KITTI's vertical-angle correction), so their rows match
# kitti_raw_3's. Needs semlio_run built with the bag readers
# (SEMLIO_WITH_BAGS; the probe reads one frame).
if [[ -x "$BIN/semlio_run" ]] && "$BIN/semlio_run" --input tests/data/bags/kitti3_lz4.bag --last 0 --map off \
  --quiet --out "$OUT/bag_probe" > /dev/null 2>&1; then
  kitti=(--sensor hdl64e --kitti-correction on)
  recording bag_kitti3 tests/data/bags/kitti3_lz4.bag "KITTI raw HDL-64E in a ROS 1 bag (lz4)" "${kitti[@]}"
  recording mcap_kitti3 tests/data/bags/kitti3_zstd.mcap "KITTI raw HDL-64E in an MCAP file (zstd)" "${kitti[@]}"
fi
# BAGS="FILE ...": your own recordings (ROS 1 bag, MCAP, rosbag2 .db3), lidar only, no reference.
for bag in ${BAGS:-}; do
  stem=$(basename "$bag")
  recording "rec_${stem%.*}" "$bag" "recording $stem"
done
if [[ $QUICK == 0 ]]; then
  if [[ -n "${KITTI_RAW:-}" ]]; then pcd_folder kitti_raw_snippet "$KITTI_RAW"; fi
  if [[ -n "${KITTI_RAW_DRIVE:-}" ]]; then
    drive=${KITTI_RAW_DRIVE%/}
    date_part=$(basename "$drive" | cut -c1-10)
    calib=${KITTI_RAW_CALIB:-$(dirname "$drive")/calib_$date_part}
    name=kitti_raw_$(basename "$drive" | sed -n 's/.*drive_\([0-9]*\).*/\1/p')
  fi
  if [[ -n "${KITTI_RAW_DRIVE:-}" ]] && wanted "$name"; then
    /usr/bin/python3 scripts/kitti_raw_drive.py "$drive" "$calib" "$OUT/data/$name"
    printf 'deskew: {mode: constant_velocity, point_times: azimuth}\n' > "$OUT/configs/$name.extra.yaml"
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$OUT/data/$name" real "KITTI raw $(basename "$drive")" \
      geometric "$OUT/configs/$name.extra.yaml" "OXTS GNSS/INS (~0.5 m)" >> "$DS"
    # The same drive read as published by semlio_run, lidar only and with its
    # OXTS IMU (the page's "Lidar-inertial on a real drive").
    if [[ -x "$BIN/semlio_run" ]]; then
      echo "== $name: lidar-only and lidar-inertial (scripts/kitti_raw_drive.sh)"
      mkdir -p "$OUT/lio"
      SKIP_BUILD=1 BUILD_DIR="$BUILD_DIR" OUT="$OUT/lio/$name" REPORT_ONLY=1 scripts/kitti_raw_drive.sh "$drive" \
        > "$OUT/lio/$name.txt" 2>&1 || { cat "$OUT/lio/$name.txt" >&2; exit 1; }
    fi
  fi
  if [[ -n "${BALM_OS0:-}" ]] && wanted balm_os0; then
    # A KITTI-layout folder of another sensor: semlio_run (not semlio_kitti)
    # reads it, so that the beam table is detected rather than KITTI's assumed.
    printf 'sensor: {profile: auto, platform: hand_held}\n' > "$OUT/configs/balm_os0.sensor.yaml"
    printf '%s\n' --format kitti --sensor "$OUT/configs/balm_os0.sensor.yaml" --kitti-correction off \
      > "$OUT/configs/balm_os0.args"
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' balm_os0 "${BALM_OS0%/}" real "hand-held OS0-class keyframes (BALM)" \
      geometric - "BALM odometry (not ground truth; cm-consistent)" >> "$DS"
  fi
  if [[ -n "${KITTI_ROOT:-}" ]] && wanted "kitti_$(basename "${KITTI_ROOT%/}")"; then
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "kitti_$(basename "${KITTI_ROOT%/}")" "${KITTI_ROOT%/}" real \
      "KITTI odometry $(basename "${KITTI_ROOT%/}")" geometric - "KITTI ground truth" >> "$DS"
  fi
fi

# --- runs --------------------------------------------------------------------
while IFS=$'\t' read -r name dir kind scene labels extra ref; do
  last=()
  if [[ "$name" == kitti_[0-9]* && -n "${KITTI_FRAMES:-}" ]]; then last=(--last $((KITTI_FRAMES - 1))); fi
  for c in "${CONFIGS[@]}"; do
    read -r cname preset <<< "$c"
    lab=$labels
    cfg="$OUT/configs/$name.$cname.yaml"
    cat "$OUT/configs/$cname.yaml" > "$cfg"
    if [[ "$extra" != - ]]; then cat "$extra" >> "$cfg"; fi
    # Both files are YAML maps; "{}" plus a second map is not one: drop it.
    sed -i '/^{}$/d' "$cfg"
    [[ -s "$cfg" ]] || echo "{}" > "$cfg"
    # A folder is a KITTI layout (semlio_kitti); a file is a recording, and a
    # folder with semlio_run options (configs/NAME.args) another sensor's
    # KITTI layout (semlio_run).
    if [[ -f "$dir" || -f "$OUT/configs/$name.args" ]]; then
      tool=(semlio_run --input "$dir")
      while read -r a; do [[ -n "$a" ]] && tool+=("$a"); done < "$OUT/configs/$name.args"
    else
      tool=(semlio_kitti --sequence "$dir")
    fi
    echo "== $name: $cname (${tool[0]} --preset $preset --labels $lab)"
    "$BIN/${tool[0]}" "${tool[@]:1}" --preset "$preset" --labels "$lab" --config "$cfg" --map off \
      "${last[@]}" --out "$OUT/runs/$name/$cname" --quiet --overwrite > "$OUT/runs/$name.$cname.log" 2>&1 ||
      { cat "$OUT/runs/$name.$cname.log" >&2; exit 1; }
  done
  # The scans of simulated drives are large (~16 MB per frame) and no longer needed.
  if [[ "$kind" == simulated ]]; then rm -rf "$dir/velodyne"; fi
done < "$DS"

# --- segmenter per-class IoU (simulated worlds and the real labelled scans) ---
echo "== segmenter IoU"
if [[ $QUICK == 1 ]]; then miou_frames=1; else miou_frames=5; fi
SKIP_BUILD=1 BUILD_DIR="$BUILD_DIR" scripts/segmenter_miou.sh "$miou_frames" "$SEED" \
  tests/data/kitti/sequences/00 tests/data/kitti/semantickitti_00_labels > "$OUT/segmenter_iou.md"

# --- the page ----------------------------------------------------------------
echo "end: $(load_now)" >> "$OUT/load.txt"
mode=full
[[ $QUICK == 1 ]] && mode=quick
args=("$OUT" --mode "$mode" --seconds $(( $(date +%s) - start )))
[[ $PLOTS == 1 ]] && args+=(--figures "$OUT/figures")
/usr/bin/python3 scripts/reproduce_report.py "${args[@]}" > "$OUT/results.md"
if [[ $QUICK == 1 ]]; then
  if [[ $CHECK == 1 ]]; then
    if ! diff -u docs/results_quick.md "$OUT/results.md"; then
      echo "reproduce.sh: the --quick results differ from docs/results_quick.md (above);" \
           "rerun scripts/reproduce.sh --quick and commit docs/results_quick.md if the change is intended" >&2
      exit 1
    fi
    echo "== docs/results_quick.md matches this build's --quick run"
  else
    cp "$OUT/results.md" docs/results_quick.md
    echo "== wrote docs/results_quick.md"
  fi
else
  mkdir -p docs/figures
  rm -f docs/figures/*.png
  cp "$OUT"/figures/*.png docs/figures/
  cp "$OUT/results.md" docs/results.md
  /usr/bin/python3 scripts/reproduce_report.py "$OUT" --mode full --readme README.md > /dev/null
  echo "== wrote docs/results.md, docs/figures/ and README.md's results block"
fi
echo "== done in $(( $(date +%s) - start )) s"
