#!/usr/bin/python3
"""One table of the runs of a batch (scripts/batch.sh, or the Slurm job array
of docs/batch.md): OUT/summary.csv and OUT/summary.md, the Markdown table also
printed.

usage: batch_table.py OUT

Reads OUT/jobs.tsv (run name <TAB> input), OUT/runs/<name>/report.json and,
when present, OUT/joblog.tsv (GNU parallel's joblog: exit code and run time)
or OUT/runs/<name>/exit_code (one number, as the Slurm array writes it). A run
without a report.json gets a row with its exit code and "no report".
Plain Python, no third-party imports.
"""
import csv
import json
import os
import sys

COLUMNS = ["run", "input", "format", "exit", "status", "preset", "labels", "frames", "keyframes",
           "ate_rmse_m", "ate_keyframes_rmse_m", "t_err_pct", "r_err_deg_per_100m",
           "frame_ms_median", "frame_ms_p95", "wall_s"]


def get(d, *path):
    for p in path:
        if not isinstance(d, dict) or p not in d:
            return None
        d = d[p]
    return d


def read_jobs(out):
    path = os.path.join(out, "jobs.tsv")
    jobs = []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            if not line.strip():
                continue
            v = line.rstrip("\n").split("\t")
            if len(v) != 2:
                sys.exit(f"{path}:{n}: expected 'name<TAB>input'")
            jobs.append(v)
    return jobs


def read_joblog(out):
    """name -> (exit code, run time s) from GNU parallel's joblog (the command holds the name)."""
    path = os.path.join(out, "joblog.tsv")
    codes = {}
    if not os.path.exists(path):
        return codes
    with open(path) as f:
        rows = list(csv.reader(f, delimiter="\t"))
    if not rows:
        return codes
    head = rows[0]
    try:
        i_exit, i_time, i_cmd = head.index("Exitval"), head.index("JobRuntime"), head.index("Command")
    except ValueError:
        sys.exit(f"{path}: not a GNU parallel joblog (no Exitval/JobRuntime/Command columns)")
    for r in rows[1:]:
        if len(r) <= max(i_exit, i_time, i_cmd):
            continue
        words = r[i_cmd].split()
        if len(words) >= 2:
            codes[words[1].strip("'\"")] = (int(r[i_exit]), float(r[i_time]))
    return codes


def fmt(v, spec):
    return "" if v is None else format(v, spec)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    jobs = read_jobs(out)
    joblog = read_joblog(out)
    rows = []
    for name, inp in jobs:
        run = os.path.join(out, "runs", name)
        code = joblog.get(name, (None, None))[0]
        code_file = os.path.join(run, "exit_code")
        if code is None and os.path.exists(code_file):
            code = int(open(code_file).read().strip() or -1)
        row = {c: None for c in COLUMNS}
        row.update(run=name, input=inp, exit=code)
        rp = os.path.join(run, "report.json")
        if os.path.exists(rp):
            try:
                r = json.load(open(rp))
            except ValueError as e:
                r = {}
                row["status"] = f"bad report.json: {e}"
            frames = r.get("frames")
            kitti = get(r, "evaluation", "kitti") if get(r, "evaluation", "kitti", "segments") else None
            row.update(format=get(r, "input", "format") or ("kitti" if r.get("schema", "").startswith("semlio_kitti") else None),
                       status=row["status"] or r.get("status", "complete"), preset=r.get("preset"), labels=r.get("labels"),
                       frames=len(frames) if isinstance(frames, list) else None, keyframes=r.get("keyframe_count"),
                       ate_rmse_m=get(r, "evaluation", "ate_all_frames", "rmse_m"),
                       ate_keyframes_rmse_m=get(r, "evaluation", "ate_keyframes", "rmse_m"),
                       t_err_pct=get(kitti, "translation_error_pct"),
                       r_err_deg_per_100m=get(kitti, "rotation_error_deg_per_100m"),
                       frame_ms_median=get(r, "frame_time_ms", "median"), frame_ms_p95=get(r, "frame_time_ms", "p95"),
                       wall_s=r.get("wall_time_s"))
        else:
            row["status"] = "no report"
        rows.append(row)

    with open(os.path.join(out, "summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        for row in rows:
            w.writerow({k: ("" if v is None else v) for k, v in row.items()})

    specs = {"ate_rmse_m": ".3f", "ate_keyframes_rmse_m": ".3f", "t_err_pct": ".3f", "r_err_deg_per_100m": ".4f",
             "frame_ms_median": ".1f", "frame_ms_p95": ".1f", "wall_s": ".1f"}
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    for row in rows:
        cells = [fmt(row[c], specs[c]) if c in specs else ("" if row[c] is None else str(row[c])) for c in COLUMNS]
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    ok = sum(1 for r in rows if r["exit"] == 0 and r["status"] in ("complete",))
    lines += ["", f"{ok} of {len(rows)} runs complete."]
    text = "\n".join(lines) + "\n"
    with open(os.path.join(out, "summary.md"), "w") as f:
        f.write(text)
    sys.stdout.write(text)


if __name__ == "__main__":
    main()
