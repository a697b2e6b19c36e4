#!/usr/bin/env python3
"""Summarise run_twist_benchmark.sh output: RESULTS_DIR/raw.jsonl -> runs.csv, summary.csv,
summary.md (median over repetitions per case and configuration)."""

import csv
import json
import statistics
import sys
from pathlib import Path

RUN_FIELDS = [
    "case_size", "case_E", "config", "rep", "solver", "mesh", "nodes", "tets", "E", "threads",
    "tolerance", "mass_preconditioner", "substeps", "status", "stable", "steps_done",
    "steps_per_s", "ms_median", "ms_p95", "ms_mean", "ms_max", "cpu_ms_per_step",
    "iterations_mean", "iterations_max", "not_converged_steps", "peak_rss_mb", "setup_rss_mb",
    "setup_s", "max_speed", "driven_error", "tip_angle", "err_z25", "err_z50", "err_z75",
    "angle_z25", "angle_z50", "angle_z75", "detail", "message",
]


def slice_values(run, key):
    values = [s.get(key) for s in run.get("slices", [])]
    return (values + [None, None, None])[:3]


def flatten(run):
    row = {k: run.get(k) for k in RUN_FIELDS}
    row["err_z25"], row["err_z50"], row["err_z75"] = slice_values(run, "error")
    row["angle_z25"], row["angle_z50"], row["angle_z75"] = slice_values(run, "angle")
    return row


def median(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def fmt(value, spec):
    return "n/a" if value is None else format(value, spec)


def main():
    results = Path(sys.argv[1])
    runs = [json.loads(line) for line in (results / "raw.jsonl").read_text().splitlines() if line.strip()]
    rows = [flatten(r) for r in runs]
    with open(results / "runs.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=RUN_FIELDS)
        writer.writeheader()
        writer.writerows(rows)

    groups = {}
    order = []
    for row in rows:
        key = (row["case_size"], row["case_E"], row["config"])
        if key not in groups:
            groups[key] = []
            order.append(key)
        groups[key].append(row)

    summary = []
    for key in order:
        g = groups[key]
        first = g[0]
        sps = [r["steps_per_s"] for r in g if r["steps_per_s"] is not None]
        summary.append({
            "case_size": key[0], "case_E": key[1], "config": key[2],
            "tets": first["tets"], "nodes": first["nodes"], "reps": len(g),
            "status": ",".join(sorted({str(r["status"]) for r in g})),
            "steps_per_s": median(sps),
            "steps_per_s_min": min(sps) if sps else None,
            "steps_per_s_max": max(sps) if sps else None,
            "ms_median": median([r["ms_median"] for r in g]),
            "ms_p95": median([r["ms_p95"] for r in g]),
            "cpu_ms_per_step": median([r["cpu_ms_per_step"] for r in g]),
            "iterations_mean": median([r["iterations_mean"] for r in g]),
            "iterations_max": max((r["iterations_max"] or 0) for r in g),
            "not_converged_steps": max((r["not_converged_steps"] or 0) for r in g),
            "peak_rss_mb": median([r["peak_rss_mb"] for r in g]),
            "err_z25": median([r["err_z25"] for r in g]),
            "err_z50": median([r["err_z50"] for r in g]),
            "err_z75": median([r["err_z75"] for r in g]),
            "max_speed": max((r["max_speed"] or 0) for r in g),
            "detail": first["detail"],
        })
    fields = list(summary[0].keys()) if summary else []
    with open(results / "summary.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        writer.writerows(summary)

    lines = []
    machine = results / "machine.txt"
    if machine.exists():
        lines += ["```", machine.read_text().rstrip(), "```", ""]
    lines += [
        "Median over repetitions (steps/s also min-max). ms = wall clock per step of dt = 0.01 s "
        "(all substeps); CPU ms = process CPU time per step (all threads); iterations = linear-solver "
        "iterations per step (mean / max); err = |theta(z) - (pi/2) z/L| / ((pi/2) z/L) at step 600; "
        "x Bullet = steps/s over 'bullet-implicit default' steps/s of the same case.",
        "",
    ]
    cases = []
    for s in summary:
        if (s["case_size"], s["case_E"]) not in cases:
            cases.append((s["case_size"], s["case_E"]))
    for size, E in cases:
        rows_case = [s for s in summary if (s["case_size"], s["case_E"]) == (size, E)]
        base = next((s["steps_per_s"] for s in rows_case if s["config"] == "bullet-implicit default"), None)
        lines.append(f"### cylinder_{size} ({rows_case[0]['tets']} tets, {rows_case[0]['nodes']} nodes), E = {E:g} Pa")
        lines.append("")
        lines.append("| configuration | steps/s (min-max) | x Bullet | ms median | ms p95 | CPU ms | iterations | peak RSS MB | err z=2.5 | err z=5 | err z=7.5 | status | reps |")
        lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for s in rows_case:
            ratio = (s["steps_per_s"] / base) if (base and s["steps_per_s"]) else None
            lines.append(
                f"| {s['config']} | {fmt(s['steps_per_s'], '.1f')} ({fmt(s['steps_per_s_min'], '.1f')}-{fmt(s['steps_per_s_max'], '.1f')}) "
                f"| {fmt(ratio, '.2f')} | {fmt(s['ms_median'], '.2f')} | {fmt(s['ms_p95'], '.2f')} "
                f"| {fmt(s['cpu_ms_per_step'], '.2f')} | {fmt(s['iterations_mean'], '.1f')} / {s['iterations_max']} "
                f"| {fmt(s['peak_rss_mb'], '.1f')} | {fmt(s['err_z25'], '.4f')} | {fmt(s['err_z50'], '.4f')} "
                f"| {fmt(s['err_z75'], '.4f')} | {s['status']} | {s['reps']} |")
        lines.append("")
    search = results / "search.jsonl"
    if search.exists():
        lines += ["Explicit substep search (bullet-explicit; first stable count is used):", "",
                  "| mesh | E | substeps | status | steps done | max speed m/s |", "|---|---|---|---|---|---|"]
        for line in search.read_text().splitlines():
            if not line.strip():
                continue
            j = json.loads(line)
            lines.append(f"| {j['mesh']} | {j['E']:g} | {j['substeps']} | {j['status']} | {j['steps_done']} | {fmt(j['max_speed'], '.3g')} |")
        lines.append("")
    (results / "summary.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
