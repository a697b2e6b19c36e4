#!/usr/bin/env python3
"""Summarise run_hyperelastic_twist.sh output: RESULTS_DIR/raw.jsonl (+ reference.jsonl, curves/)
-> runs.csv, summary.csv, summary.md. Usage: summarize_hyperelastic_twist.py RESULTS_DIR MESH.node

Accuracy columns: the end torque (rep 1's curve) at the end of the ramp and at the last step, over
St-Venant's mu (pi a^4 / 2) angle / L; and the deviation of the final positions from the family's
reference, |x - x_ref| / |x_ref - X|: ours against ours neo-Hookean solved tightly
(reference.jsonl), Bullet's against Bullet's neo-Hookean at its default CG tolerance."""

import csv
import json
import math
import statistics
import sys
from pathlib import Path

OURS_NH = "ours_nh"
BULLET_REF = "bullet_nh_default"


def median(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def fmt(value, spec):
    return "n/a" if value is None else format(value, spec)


def read_nodes(path):
    rows = [line.split() for line in Path(path).read_text().splitlines()
            if line.strip() and not line.lstrip().startswith("#")]
    count = int(rows[0][0])
    return [tuple(float(v) for v in r[1:4]) for r in rows[1:count + 1]]


def read_positions(path):
    if not Path(path).exists():
        return None
    return [tuple(float(v) for v in line.split()) for line in Path(path).read_text().splitlines()
            if line.strip()]


def deviation(x, ref, rest):
    if x is None or ref is None or len(x) != len(ref):
        return None
    num = sum((a - b) ** 2 for p, q in zip(x, ref) for a, b in zip(p, q))
    den = sum((a - b) ** 2 for p, q in zip(ref, rest) for a, b in zip(p, q))
    return math.sqrt(num / den) if den > 0 else None


def read_curve(path):
    if not Path(path).exists():
        return []
    with open(path) as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def tail_range(curve, count=100):
    """Smallest and largest torque over the last `count` steps (the ringing of the hold phase)."""
    tail = [p["torque"] for p in curve[-count:]]
    return (min(tail), max(tail)) if tail else (None, None)


def ramp_and_end_torque(curve):
    """Torque at the first step where the prescribed angle reaches its final value, and at the
    last step."""
    if not curve:
        return None, None
    final = curve[-1]["angle"]
    ramp = next((p for p in curve if p["angle"] >= final - 1e-12), curve[-1])
    return ramp["torque"], curve[-1]["torque"]


def main():
    results = Path(sys.argv[1])
    rest = read_nodes(sys.argv[2]) if len(sys.argv) > 2 else None
    runs = [json.loads(l) for l in (results / "raw.jsonl").read_text().splitlines() if l.strip()]
    curves = results / "curves"

    fields = ["config", "key", "rep", "solver", "law", "status", "steps_done", "steps_per_s",
              "ms_median", "ms_mean", "ms_p95", "cpu_ms_per_step", "newton_mean", "newton_max",
              "iterations_mean", "iterations_max", "iterations_total", "not_converged_steps",
              "newton_not_converged_steps", "line_search_cuts", "projected_iterations",
              "end_torque", "torque_st_venant", "tip_angle", "peak_rss_mb", "detail", "message"]
    with open(results / "runs.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields + ["err_z25", "err_z50", "err_z75"])
        writer.writeheader()
        for r in runs:
            row = {k: r.get(k) for k in fields}
            errors = ([s.get("error") for s in r.get("slices", [])] + [None] * 3)[:3]
            row["err_z25"], row["err_z50"], row["err_z75"] = errors
            writer.writerow(row)

    ref_ours = read_positions(curves / "reference_ours_nh.pos")
    ref_bullet = read_positions(curves / f"{BULLET_REF}_rep1.pos")

    order, groups = [], {}
    for r in runs:
        if r["key"] not in groups:
            groups[r["key"]] = []
            order.append(r["key"])
        groups[r["key"]].append(r)

    summary = []
    for key in order:
        g = groups[key]
        first = g[0]
        sps = [r.get("steps_per_s") for r in g if r.get("steps_per_s")]
        errors = [[(s.get("error")) for s in r.get("slices", [])] for r in g]
        curve = read_curve(curves / f"{key}_rep1.csv")
        ramp_torque, end_torque = ramp_and_end_torque(curve)
        tail_min, tail_max = tail_range(curve)
        x = read_positions(curves / f"{key}_rep1.pos")
        is_bullet = str(first.get("solver", "")).startswith("bullet")
        ref = ref_bullet if is_bullet else ref_ours
        summary.append({
            "config": first["config"], "key": key, "reps": len(g),
            "status": ",".join(sorted({str(r.get("status")) for r in g})),
            "steps_per_s": median(sps), "steps_per_s_min": min(sps) if sps else None,
            "steps_per_s_max": max(sps) if sps else None,
            "ms_median": median([r.get("ms_median") for r in g]),
            "ms_mean": median([r.get("ms_mean") for r in g]),
            "cpu_ms_per_step": median([r.get("cpu_ms_per_step") for r in g]),
            "newton_mean": median([r.get("newton_mean") for r in g]),
            "newton_max": max((r.get("newton_max") or 0) for r in g) if first.get("newton_max") is not None else None,
            "cg_mean": median([r.get("iterations_mean") for r in g]),
            "cg_total": median([r.get("iterations_total") for r in g]),
            "not_converged": max((r.get("not_converged_steps") or 0) + (r.get("newton_not_converged_steps") or 0) for r in g),
            "err_z25": median([e[0] if len(e) > 0 else None for e in errors]),
            "err_z50": median([e[1] if len(e) > 1 else None for e in errors]),
            "err_z75": median([e[2] if len(e) > 2 else None for e in errors]),
            "torque_ramp_end": ramp_torque, "torque_end": end_torque,
            "torque_tail_min": tail_min, "torque_tail_max": tail_max,
            "torque_st_venant": first.get("torque_st_venant"),
            "deviation": deviation(x, ref, rest) if rest else None,
            "deviation_ref": "Bullet NH default" if is_bullet else "ours NH tight",
            "peak_rss_mb": median([r.get("peak_rss_mb") for r in g]),
            "detail": first.get("detail"),
        })
    base = next((s for s in summary if s["key"] == OURS_NH), None)
    for s in summary:
        s["cost_vs_ours_nh"] = (base["steps_per_s"] / s["steps_per_s"]
                                if base and base["steps_per_s"] and s["steps_per_s"] else None)
        s["cpu_vs_ours_nh"] = (s["cpu_ms_per_step"] / base["cpu_ms_per_step"]
                               if base and base["cpu_ms_per_step"] and s["cpu_ms_per_step"] else None)
    with open(results / "summary.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(summary[0].keys()) if summary else [])
        writer.writeheader()
        writer.writerows(summary)

    lines = []
    machine = results / "machine.txt"
    if machine.exists():
        lines += ["```", machine.read_text().rstrip(), "```", ""]
    first = runs[0] if runs else {}
    lines += [
        f"Cylinder twist, {first.get('mesh')} ({first.get('tets')} tets, {first.get('nodes')} nodes), "
        f"E = {first.get('E', 0):g} Pa, nu = {first.get('nu')}, {first.get('steps')} steps of dt = "
        f"{first.get('dt')} s, 1 thread. Medians over repetitions (steps/s also min-max). ms = wall "
        "clock per step (median step), CPU ms = process CPU per step; Newton = linear solves per "
        "step (mean / max; Bullet: its fixed count); CG = CG iterations per step, all Newton "
        "solves together (mean; total over the run); cost = ours neo-Hookean steps/s over the "
        "row's (how many times slower than ours neo-Hookean), CPU x = the row's CPU ms over ours "
        "neo-Hookean's; err = |theta(z) - (pi/2) z/L| / ((pi/2) z/L) at the last step; torque = "
        "the driver's torque about z at the end of the ramp and at the last step (rep 1), and the "
        "last over St-Venant's; last 100 = its range over the last 100 steps (the hold phase still "
        "rings where damping is weak, so the last step's angles and torque are a snapshot of that "
        "oscillation); deviation = |x - x_ref| / |x_ref - X| of rep 1's final positions "
        "against the reference named.",
        "",
        "| configuration | steps/s (min-max) | ms median | CPU ms | cost | CPU x | Newton | CG | "
        "err z=L/4 | err z=L/2 | err z=3L/4 | torque ramp end, N m | torque end, N m (/ St-Venant) | "
        "last 100, N m | deviation (reference) | unconverged | status | reps |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for s in summary:
        ratio = (s["torque_end"] / s["torque_st_venant"]
                 if s["torque_end"] is not None and s["torque_st_venant"] else None)
        newton = ("-" if s["newton_mean"] is None
                  else f"{s['newton_mean']:.2f} / {s['newton_max']}")
        lines.append(
            f"| {s['config']} | {fmt(s['steps_per_s'], '.1f')} ({fmt(s['steps_per_s_min'], '.1f')}-"
            f"{fmt(s['steps_per_s_max'], '.1f')}) | {fmt(s['ms_median'], '.2f')} "
            f"| {fmt(s['cpu_ms_per_step'], '.2f')} | {fmt(s['cost_vs_ours_nh'], '.2f')} "
            f"| {fmt(s['cpu_vs_ours_nh'], '.2f')} | {newton} "
            f"| {fmt(s['cg_mean'], '.1f')} ({fmt(s['cg_total'], '.0f')}) "
            f"| {fmt(s['err_z25'], '.4f')} | {fmt(s['err_z50'], '.4f')} | {fmt(s['err_z75'], '.4f')} "
            f"| {fmt(s['torque_ramp_end'], '.0f')} | {fmt(s['torque_end'], '.0f')} ({fmt(ratio, '.3f')}) "
            f"| {fmt(s['torque_tail_min'], '.0f')}-{fmt(s['torque_tail_max'], '.0f')} "
            f"| {fmt(s['deviation'], '.2e')} ({s['deviation_ref']}) | {s['not_converged']} "
            f"| {s['status']} | {s['reps']} |")
    lines.append("")
    if ref_ours and ref_bullet and rest:
        lines.append("Model difference, final positions: ours neo-Hookean (tight) against Bullet's "
                     f"neo-Hookean (default tolerance): {fmt(deviation(ref_bullet, ref_ours, rest), '.2e')}; "
                     "ours corotated against ours neo-Hookean (tight): "
                     f"{fmt(deviation(read_positions(curves / 'ours_corot_rep1.pos'), ref_ours, rest), '.2e')}.")
        lines.append("")
    lines.append("Details: " + "; ".join(f"{s['config']}: {s['detail']}" for s in summary))
    (results / "summary.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
