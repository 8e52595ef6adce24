#!/usr/bin/python3
"""Prints two or more semlio_kitti report.json files side by side."""
import json
import sys


def get(d, *path, default=None):
    for p in path:
        if not isinstance(d, dict) or p not in d:
            return default
        d = d[p]
    return d


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


def main():
    reports = [json.load(open(p)) for p in sys.argv[1:]]
    names = [r.get("preset", p) for r, p in zip(reports, sys.argv[1:])]
    rows = [
        ("frames", lambda r: len(r["frames"]), "d"),
        ("keyframes", lambda r: r["keyframe_count"], "d"),
        ("ATE RMSE all frames [m]", lambda r: get(r, "evaluation", "ate_all_frames", "rmse_m"), ".3f"),
        ("ATE RMSE keyframes [m]", lambda r: get(r, "evaluation", "ate_keyframes", "rmse_m"), ".3f"),
        ("KITTI t_err [%]", lambda r: get(r, "evaluation", "kitti", "translation_error_pct"), ".3f"),
        ("KITTI r_err [deg/100m]", lambda r: get(r, "evaluation", "kitti", "rotation_error_deg_per_100m"), ".4f"),
        ("frame time median [ms]", lambda r: r["frame_time_ms"]["median"], ".1f"),
        ("frame time p95 [ms]", lambda r: r["frame_time_ms"]["p95"], ".1f"),
        ("ranks 6-15 used [%]", lambda r: 100.0 * sum(r["association_rank_histogram"][5:]) / max(1, sum(r["association_rank_histogram"])), ".1f"),
    ]
    width = max(len(n) for n in names) + 2
    print(f"{'':26}" + "".join(f"{n:>{max(width, 12)}}" for n in names))
    for label, fn, spec in rows:
        print(f"{label:26}" + "".join(f"{fmt(fn(r), spec):>{max(width, 12)}}" for r in reports))
    ates = [get(r, "evaluation", "ate_all_frames", "rmse_m") for r in reports]
    if len(reports) == 2 and all(a is not None for a in ates) and ates[0] > 0:
        print(f"{names[1]} vs {names[0]}: ATE {100.0 * (ates[1] - ates[0]) / ates[0]:+.1f} %")


if __name__ == "__main__":
    main()
