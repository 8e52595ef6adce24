#!/usr/bin/env python3
"""Writes docs/data_sources.md and the README's sources block from the
outputs of scripts/data_sources.sh.

Usage: data_sources_page.py OUT DRIVE_NAME PAGE README SECONDS
  OUT: data_sources.sh's output folder (drive/summary.tsv,
       balm_{baseline,full}/evaluation.json, sensors/summary.tsv)
  README: the README to update between <!-- sources:begin --> and
       <!-- sources:end --> ("" = leave it)."""
import json
import os
import sys

from page_util import cpu_name, replace_readme_block, verdict

SENSOR_NAMES = {"vlp16": "VLP-16", "os1-64": "OS1-64", "os0-128": "OS0-128"}
BEAM_SOURCES = {"scan_rings": "the ring field", "elevation": "detected from elevations",
                "point_order": "KITTI point order", "uniform_fallback": "not separable: uniform bands"}
INPUT_NAMES = {
    "drive": "KITTI-layout folder",
    "with_fields.bag": "ROS 1 bag, ring + time fields",
    "with_fields.mcap": "MCAP, ring + time fields",
    "no_fields.bag": "ROS 1 bag, x y z intensity only",
}


def read_tsv(path):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [line.rstrip("\n").split("\t") for line in f if line.strip()]


def drive_section(out, drive):
    rows = read_tsv(os.path.join(out, "drive", "summary.tsv"))
    if not rows:
        return [], []
    page = [
        f"## A real KITTI raw drive, read as published",
        "",
        f"`{drive}` exactly as KITTI publishes it (velodyne_points/ with the blank lines its "
        "timestamps.txt has where the recorder dropped sweeps, oxts/, the day's calibration files beside it), "
        "read by `semlio_run --input DRIVE` (`scripts/kitti_raw_drive.sh`; labels: none). The reference is the "
        "OXTS GNSS/INS trajectory, whose positions jitter by about 5 cm. Path length within 1 % of the OXTS one "
        "and ATE (SE(3)-aligned) at most 0.15 m; with the IMU also initialised by frame 10 and no worse than "
        "the same preset lidar-only in ATE and end-point rotation.",
        "",
        "| preset | IMU | frames | path [m] | OXTS path [m] | ATE [m] | end rotation [deg] | IMU initialised at frame | holds |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    summary = []
    for preset, imu, frames, path, ref, ate, end_deg, init, _deskewed, ok, _why in rows:
        page.append(f"| {preset} | {'OXTS' if imu == 'on' else 'none'} | {frames} | {path} | {ref} | {ate} | "
                    f"{end_deg} | {init} | {verdict(ok == 'PASS')} |")
    for imu in ("none", "on"):
        sel = [r for r in rows if r[1] == imu]
        if not sel:
            continue
        worst_path = max(abs(float(r[3]) - float(r[4])) / float(r[4]) * 100 for r in sel)
        worst_ate = max(float(r[5]) for r in sel)
        ok = all(r[9] == "PASS" for r in sel)
        label = "lidar only" if imu == "none" else "with its OXTS IMU"
        summary.append(f"| real KITTI raw drive as published, {label} ({', '.join(r[0] for r in sel)}) | "
                       f"path within {worst_path:.2f} % of OXTS, ATE {worst_ate:.3f} m | 1 %, 0.15 m"
                       f"{', IMU no worse than lidar only' if imu == 'on' else ''} | {verdict(ok)} |")
    return page + [""], summary


def balm_section(out):
    runs = []
    for preset in ("baseline", "full"):
        path = os.path.join(out, f"balm_{preset}", "evaluation.json")
        if os.path.exists(path):
            with open(path) as f:
                runs.append((preset, json.load(f)))
    if not runs:
        return [], []
    page = [
        "## Real hand-held OS0-class keyframes",
        "",
        "The 60 BALM keyframes of a hand-held OS0-class spinning lidar with a 90-degree vertical field (beam "
        "count not stated by the recording; 0.5 s apart, rotations up to 48 deg between keyframes, no ring or "
        "time fields), read by `semlio_run` with `sensor: {profile: "
        "auto, platform: hand_held}` (`scripts/balm_os0.sh`). The reference poses are a consistent odometry of "
        "the same data, not ground truth. Beam table detected and reported, no frame lost or rejected, median "
        "keyframe-to-keyframe difference to the reference within 5 cm / 0.5 deg, ATE at most 0.10 m.",
        "",
        "| preset | beams found | how | profile matched | points on a beam | frames tracked | median step difference | "
        "largest step difference | ATE [m] | holds |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for preset, e in runs:
        s = e["sensor"]
        tracked = e["statuses"].get("tracked", 0) + e["statuses"].get("initialized", 0)
        fit = s.get("detection_fit_fraction")
        fit_text = f"{float(fit) * 100:.1f} %" if fit is not None else "-"
        page.append(
            f"| {preset} | {s.get('beams', '?')} | {s.get('detection', '?')} | "
            f"{s.get('matched_profile', 'none')} ({s.get('matched_beams', '-')} beams) | {fit_text} | "
            f"{tracked} of {e['keyframes']} | "
            f"{e['median_step_difference_m'] * 100:.2f} cm / {e['median_step_difference_deg']:.3f} deg | "
            f"{e['max_step_difference_m'] * 100:.2f} cm / {e['max_step_difference_deg']:.3f} deg | "
            f"{e['ate_m']:.4f} | {verdict(e['pass'])} |")
    worst_cm = max(e["median_step_difference_m"] * 100 for _, e in runs)
    worst_deg = max(e["median_step_difference_deg"] for _, e in runs)
    worst_ate = max(e["ate_m"] for _, e in runs)
    lost = sum(e["lost"] for _, e in runs)
    beams = " / ".join(dict.fromkeys(str(e["sensor"].get("beams", "?")) for _, e in runs))
    matched = " / ".join(dict.fromkeys(str(e["sensor"].get("matched_profile", "no profile")) for _, e in runs))
    summary = [f"| real hand-held OS0-class keyframes ({', '.join(p for p, _ in runs)}) | {beams} beams detected "
               f"({matched}), "
               f"{lost} frames lost, median step difference {worst_cm:.2f} cm / {worst_deg:.3f} deg, "
               f"ATE {worst_ate:.4f} m | no frame lost, 5 cm / 0.5 deg, 0.10 m | "
               f"{verdict(all(e['pass'] for _, e in runs))} |"]
    return page + [""], summary


def sensors_section(out):
    rows = read_tsv(os.path.join(out, "sensors", "summary.tsv"))
    if not rows:
        return [], []
    frames = rows[0][2]
    page = [
        "## Simulated sensors through each container",
        "",
        f"Urban drives with heavy traffic from semlio's simulator, {frames} frames per sensor, exact ground truth "
        "(`scripts/accuracy_sensors_bags.sh`; preset full, labels from the geometric segmenter, since bags carry "
        "no labels). Each drive is written as a KITTI-layout folder, a ROS 1 bag and an MCAP file with the "
        "drivers' ring and time fields, and a ROS 1 bag with x, y, z and intensity only (rings and point times "
        "then inferred); `semlio_run --sensor auto` reads each. KITTI t_err at most 1.0 % for the VLP-16, "
        "0.5 % for the OS1-64 and OS0-128.",
        "",
        "| sensor | input | frames | t_err [%] | r_err [deg/100 m] | bound [%] | profile (beam table from) | holds |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for sensor, inp, n, t, r, bound, ok, profile, how in rows:
        page.append(f"| {SENSOR_NAMES.get(sensor, sensor)} | {INPUT_NAMES.get(inp, inp)} | {n} | {t} | {r} | "
                    f"{bound} | {profile} ({BEAM_SOURCES.get(how, how)}) | {verdict(ok == 'PASS')} |")
    summary = []
    for sensor in dict.fromkeys(r[0] for r in rows):
        sel = [r for r in rows if r[0] == sensor]
        worst = max(float(r[3]) for r in sel)
        summary.append(f"| simulated {SENSOR_NAMES.get(sensor, sensor)}, {frames} frames: folder, ROS 1 bag and MCAP "
                       f"with fields, ROS 1 bag without | worst t_err {worst:.3f} % | {sel[0][5]} % | "
                       f"{verdict(all(r[6] == 'PASS' for r in sel))} |")
    return page + [""], summary


def main():
    if len(sys.argv) != 6:
        sys.exit(__doc__)
    out, drive, page_path, readme, seconds = sys.argv[1:6]
    sections, summary = [], []
    for part, rows in (drive_section(out, drive), balm_section(out), sensors_section(out)):
        sections += part
        summary += rows
    table = ["| must hold | measured | bound | holds |", "|---|---|---|---|"] + summary
    try:
        load = open("/proc/loadavg").read().split()[:3]
    except OSError:
        load = ["?"] * 3
    page = [
        "# Data sources and sensors",
        "",
        "Made by `scripts/data_sources.sh KITTI_RAW_DRIVE BALM_OS0_DIR [FRAMES]` (rerun it to check these "
        f"numbers; it took {int(seconds) // 60} min on {cpu_name()}, load average {' '.join(load)} at the end). "
        "How fast the containers are read against the odometry's frame rate is on "
        "[read_speed.md](read_speed.md); every KITTI-layout and simulated drive's ablation is on "
        "[results.md](results.md).",
        "",
        "## Summary",
        "",
    ] + table + [""] + sections
    with open(page_path, "w") as f:
        f.write("\n".join(page).rstrip("\n") + "\n")
    if readme:
        replace_readme_block(readme, "sources", "data_sources.sh", table)

if __name__ == "__main__":
    main()
