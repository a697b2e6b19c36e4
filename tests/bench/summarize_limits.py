"""Markdown table of run_limits.sh's results: RESULTS_DIR/raw.jsonl, drop.jsonl, machine_probe.json."""
import json
import sys
from pathlib import Path

out = Path(sys.argv[1])
rows = {}
for line in (out / "raw.jsonl").read_text().splitlines():
    entry = json.loads(line)
    rows.setdefault(entry["row"], []).append(entry)


def cell(run):
    if "run" not in run:
        return "failed"
    r = run["run"]
    text = f"**{r['steps_per_s']:.3g}** steps/s ({r['ms_median']:.2f} ms median, CPU {r['cpu_ms_per_step']:.2f} ms"
    if r["solver"].startswith("torsion"):
        text += f", {r['iterations_mean']:.1f} CG it"
    else:
        text += f", {r['iterations_mean']:.0f} Bullet CG it"
    text += f", {r['peak_rss_mb']:.0f} MB"
    if r.get("status") != "ok":
        text += f", {r.get('status')}"
    return text + f"; {r['steps_done']} steps)"


print("| row | configuration | result | x Bullet |")
print("|---|---|---|---|")
for row, runs in rows.items():
    bullet = next((r for r in runs if r["engine"] == "bullet" and "run" in r), None)
    for r in runs:
        ratio = ""
        if bullet and r is not bullet and "run" in r:
            ratio = f"{r['run']['steps_per_s'] / bullet['run']['steps_per_s']:.1f}x"
        label = r["engine"]
        if "run" in r:
            # bench_twist's "nodes" are the linear mesh's (tet10 adds a node per edge).
            label += f" ({r['run']['element']}, {r['run']['tets']} tets)"
        print(f"| {row} | {label} | {cell(r)} | {ratio} |")
drop = out / "drop.jsonl"
if drop.exists():
    runs = [json.loads(l) for l in drop.read_text().splitlines() if l.strip()]
    by = {r["engine"]: r for r in runs}
    for engine, r in by.items():
        ratio = ""
        if engine != "bullet" and "bullet" in by:
            ratio = f"{r['steps_per_second'] / by['bullet']['steps_per_second']:.1f}x"
        print(f"| drop impact 8332, 1 thread | {engine} | **{r['steps_per_second']:.1f}** steps/s "
              f"({r['steps']} steps; exploded {r['exploded']}, sank {r['sank']}) | {ratio} |")
probe = json.loads((out / "machine_probe.json").read_text())
print()
print("Machine probe: " + ", ".join(f"{k} {v}" for k, v in probe.items()))
