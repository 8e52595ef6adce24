#!/usr/bin/env python3
"""Writes docs/robustness.md and the README's robustness block from a
scripts/fuzz.sh SUMMARY file and the output of scripts/sanitize.sh address
(scripts/robustness.sh runs all three).

Usage: robustness_page.py --fuzz TSV --sanitize LOG [--sanitize-build DIR] [--interrupt LOG] --page PAGE
                           --readme README
  LOG of --interrupt: the output of scripts/interrupt_check.sh (PASS / FAIL lines).
  README "-" leaves the README alone; DIR (the sanitized build folder) names
  the compiler when the log does not."""
import argparse
import os
import re
import subprocess
import sys

from page_util import cpu_name, replace_readme_block, verdict

MIN_EXECUTIONS = 1_000_000


def read_fuzz(path):
    with open(path) as f:
        lines = [line.rstrip("\n").split("\t") for line in f if line.strip()]
    if not lines or lines[0][0] != "harness":
        sys.exit(f"{path}: not a scripts/fuzz.sh SUMMARY file (no header line)")
    keys = lines[0]
    # Several fuzz.sh runs may be concatenated (each starts with the header).
    rows = [dict(zip(keys, line)) for line in lines[1:] if line[0] != "harness"]
    for r in rows:
        for k in ("seconds", "workers", "executions", "exec_per_s", "findings"):
            r[k] = int(r[k])
    return rows


def read_sanitize(path):
    with open(path, errors="replace") as f:
        text = f.read()
    s = {"flags": None, "compiler": None, "passed": None, "failed": None, "total": None, "seconds": None,
         "failed_tests": [], "reports": 0}
    m = re.search(r"building with -fsanitize=(\S+)", text)
    s["flags"] = m.group(1) if m else None
    m = re.search(r"sanitize.sh: compiler \S+ \((.+)\)", text) or \
        re.search(r"The CXX compiler identification is (.+)", text)
    s["compiler"] = m.group(1).strip() if m else None
    m = re.search(r"(\d+)% tests passed, (\d+) tests? failed out of (\d+)", text)
    if m:
        s["failed"], s["total"] = int(m.group(2)), int(m.group(3))
        s["passed"] = s["total"] - s["failed"]
    m = re.search(r"Total Test time \(real\) = *([0-9.]+) sec", text)
    s["seconds"] = float(m.group(1)) if m else None
    if "The following tests FAILED:" in text:
        tail = text.split("The following tests FAILED:", 1)[1]
        for line in tail.splitlines()[1:]:
            t = re.match(r"\s*\d+ - (.+?) \((.+)\)$", line)
            if not t:
                break
            s["failed_tests"].append(f"{t.group(1)} ({t.group(2)})")
    s["reports"] = len(re.findall(r"ERROR: (?:AddressSanitizer|LeakSanitizer)|runtime error:", text))
    return s


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--fuzz", required=True)
    ap.add_argument("--sanitize", required=True)
    ap.add_argument("--sanitize-build", default="")
    ap.add_argument("--interrupt", default="")
    ap.add_argument("--page", required=True)
    ap.add_argument("--readme", required=True)
    a = ap.parse_args()
    fuzz = read_fuzz(a.fuzz)
    san = read_sanitize(a.sanitize)
    cache = os.path.join(a.sanitize_build, "CMakeCache.txt")
    if san["compiler"] is None and a.sanitize_build and os.path.exists(cache):
        with open(cache) as f:
            cxx = next((line.split("=", 1)[1].strip() for line in f if line.startswith("CMAKE_CXX_COMPILER:")), "")
        if cxx:
            version = subprocess.run([cxx, "--version"], capture_output=True, text=True).stdout.splitlines()
            san["compiler"] = version[0] if version else cxx
    if san["total"] is None:
        sys.exit(f"{a.sanitize}: no CTest summary (did scripts/sanitize.sh address finish?)")

    findings = sum(r["findings"] for r in fuzz)
    fewest = min(fuzz, key=lambda r: r["executions"])
    seconds = sorted({r["seconds"] for r in fuzz})
    fuzz_ok = findings == 0 and fewest["executions"] >= MIN_EXECUTIONS and seconds == [300]
    san_ok = san["failed"] == 0 and san["reports"] == 0

    summary = [
        "| must hold | measured | holds |",
        "|---|---|---|",
        f"| `scripts/fuzz.sh 300`: no finding, at least 1 million executions per reader | "
        f"{findings} findings over {len(fuzz)} harnesses, {'/'.join(map(str, seconds))} s each; fewest executions "
        f"{fewest['executions']:,} (`{fewest['harness']}`) | {verdict(fuzz_ok)} |",
        f"| `scripts/sanitize.sh address` over the whole test suite: no report | "
        f"{san['passed']} of {san['total']} tests passed, {san['reports']} sanitizer reports | {verdict(san_ok)} |",
    ]

    checks = []
    if a.interrupt:
        with open(a.interrupt) as f:
            checks = [line.rstrip("\n").split("  ", 1) for line in f if line.startswith(("PASS  ", "FAIL  "))]
        if not checks:
            sys.exit(f"{a.interrupt}: no PASS / FAIL lines (not a scripts/interrupt_check.sh output)")
        passed = sum(1 for v, _ in checks if v == "PASS")
        summary.append(f"| SIGINT after 10 frames of real KITTI raw scans: complete outputs for those frames; a second run "
                       f"refused without `--overwrite`, with it only its own files | {passed} of {len(checks)} checks "
                       f"of `scripts/interrupt_check.sh` pass | {verdict(passed == len(checks))} |")

    page = [
        "# Robustness: fuzzing, sanitizers, interrupted runs",
        "",
        "Generated by `scripts/robustness.sh` (it runs `scripts/fuzz.sh 300` and `scripts/sanitize.sh address`, "
        "then `scripts/robustness_page.py`); do not edit by hand. What the readers promise for bad input -- a "
        "typed error naming the file, line and value, never a crash -- is tested here beyond the committed "
        "cases: libFuzzer mutates every reader's input, and the whole test suite (unit tests, the replay of every "
        "fuzz seed and past crash input, the catalogue of bad inputs through the command-line tools, the tools' "
        "and scripts' end-to-end runs) runs under AddressSanitizer and UndefinedBehaviorSanitizer. "
        "The harnesses and what each checks after a successful read: [tests/fuzz/README.md](../tests/fuzz/README.md).",
        "",
        *summary,
        "",
        f"## Fuzzing ({cpu_name()}, {os.cpu_count()} cores)",
        "",
        "clang 14, `-fsanitize=fuzzer,address,undefined`, from the committed seeds of `tests/fuzz/corpus/`. "
        "A finding is an input that crashes, trips a sanitizer or breaks an invariant; `fuzz.sh` saves it into "
        "`tests/fuzz/crashes/`, which the regular test build replays. Workers: libFuzzer processes on the "
        "harness's corpus at once, their executions summed.",
        "",
        "| harness | seconds | workers | executions | exec/s | findings | >= 1 million |",
        "|---|---:|---:|---:|---:|---:|---|",
    ]
    for r in fuzz:
        page.append(f"| `{r['harness']}` | {r['seconds']} | {r['workers']} | {r['executions']:,} | {r['exec_per_s']:,} | "
                    f"{r['findings']} | {verdict(r['executions'] >= MIN_EXECUTIONS)} |")
    minutes = f"{san['seconds'] / 60:.0f} min" if san["seconds"] is not None else "unknown time"
    page += [
        "",
        "## The test suite under sanitizers",
        "",
        f"`scripts/sanitize.sh address`: {san['compiler'] or 'compiler not named in the log'}, "
        f"`-fsanitize={san['flags'] or '?'}`, `-O1 -g`, every CTest entry (ASan with leak detection; any "
        f"report stops the test and fails it). {san['passed']} of {san['total']} tests passed in {minutes}; "
        f"{san['reports']} sanitizer reports.",
    ]
    if san["failed_tests"]:
        page += ["", "Failed:", ""] + [f"- `{t}`" for t in san["failed_tests"]]
    if checks:
        page += ["", "## Interrupted runs", "",
                 "`scripts/interrupt_check.sh` on real KITTI raw scans: `semlio_run` signals itself with SIGINT after "
                 "10 frames (the real signal path), then runs again into the same OUT without and with `--overwrite`.",
                 "", "| check | result |", "|---|---|"]
        page += [f"| {what} | {'pass' if v == 'PASS' else '**fail**'} |" for v, what in checks]
    with open(a.page, "w") as f:
        f.write("\n".join(page) + "\n")

    if a.readme != "-":
        replace_readme_block(a.readme, "robustness", "robustness.sh", summary)

if __name__ == "__main__":
    main()
