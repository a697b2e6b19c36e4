#!/usr/bin/env bash
# What a rigid body resting on a large soft body costs (docs/performance-contact.md, "The contact
# island on rigid bodies"): each scene twice, with the rigid body and without it (the same body's
# step without that contact), in Torsion (`torsion run`, one thread: median and p95 ms per step from
# summary.json, the median of REPS runs) and in Bullet's btDeformableMultiBodyDynamicsWorld on the
# same mesh (bench_bullet_demos, one JSON line per engine).
#
#   slab_box      1 kg sphere (r 0.1 m) on a 1 x 1 x 0.1 m slab (E 100 kPa, base held), 12000 tets
#                 on a grid (`torsion mesh box`), CG to 1e-6, 200 steps of 10 ms
#   slab_tetgen   the same on an unstructured 13482-tet slab (`torsion mesh tetrahedralize`, TetGen)
#   cylinder      5 kg box (0.5 m) on the 8332-tet cylinder (r 1 m) lying on the ground
#                 (tests/bench/box_on_cylinder_8332.json), against the cylinder on the ground
#   cylinder_held the same box on the cylinder held by its end caps, no ground
#
# Usage: bash tests/bench/run_contact_cost.sh RESULTS_DIR
# Environment (defaults in brackets): BUILD [build], REPS [3], BULLET [1: also Bullet's solver]
# Writes RESULTS_DIR/machine.txt, the meshes and scenes it made, raw.jsonl, summary.md.
set -euo pipefail
if [[ $# -ne 1 ]]; then sed -n '2,17p' "$0"; exit 2; fi
OUT=$(mkdir -p "$1" && cd "$1" && pwd)
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-$ROOT/build}
REPS=${REPS:-3}
BULLET=${BULLET:-1}
T=$BUILD/demos/torsion
BB=$BUILD/tests/bench/bench_bullet_demos
for exe in "$T" "$BB"; do
  [[ -x $exe ]] || { echo "missing $exe (cmake --build $BUILD --target torsion bench_bullet_demos)" >&2; exit 2; }
done
{
  echo "command: bash tests/bench/run_contact_cost.sh $1 (REPS=$REPS BULLET=$BULLET)"
  echo "date: $(date -u +%FT%TZ)"
  echo "commit: $(git -C "$ROOT" rev-parse --short HEAD)$(git -C "$ROOT" diff --quiet || echo ' (plus uncommitted changes)')"
  echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), nproc $(nproc)"
  echo "load at start: $(cut -d' ' -f1-3 /proc/loadavg)"
} >"$OUT/machine.txt"

# ---- Meshes and scenes ----
"$T" mesh box --min -0.5 -0.5 -0.1 --max 0.5 0.5 0 --cells 20 20 5 -o "$OUT/slab_box.node" >/dev/null
cat >"$OUT/slab.off" <<'EOF'
OFF
8 12 0
-0.5 -0.5 -0.1
0.5 -0.5 -0.1
0.5 0.5 -0.1
-0.5 0.5 -0.1
-0.5 -0.5 0
0.5 -0.5 0
0.5 0.5 0
-0.5 0.5 0
3 0 2 1
3 0 3 2
3 4 5 6
3 4 6 7
3 0 1 5
3 0 5 4
3 1 2 6
3 1 6 5
3 2 3 7
3 2 7 6
3 3 0 4
3 3 4 7
EOF
"$T" mesh tetrahedralize "$OUT/slab.off" --max-volume 2.2e-5 -o "$OUT/slab_tetgen.node" >/dev/null
cp "$ROOT/assets/meshes/cylinder_8332.node" "$ROOT/assets/meshes/cylinder_8332.ele" "$OUT/"

python3 - "$OUT" <<'EOF'
import json, sys
out = sys.argv[1]
def write(name, scene):
    scene["name"] = name
    with open(f"{out}/{name}.json", "w") as f:
        json.dump(scene, f, indent=1)
for mesh in ("slab_box", "slab_tetgen"):
    slab = {"steps": 200, "solver": {"dt": 0.01, "tolerance": 1e-6}, "gravity": [0, 0, -9.81],
            "bodies": [{"name": "slab", "mesh": f"{mesh}.node",
                        "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3,
                                     "density": 1000, "stiffness_damping": 0.01}}],
            "node_sets": [{"name": "base", "body": "slab",
                           "select": {"plane": {"point": [0, 0, -0.1], "normal": [0, 0, 1]}}}]}
    write(f"{mesh}_alone", dict(slab))
    slab["rigid_bodies"] = [{"name": "sphere", "shape": {"sphere": {"radius": 0.1}}, "mass": 1,
                             "pose": {"position": [0, 0, 0.12]}}]
    write(f"{mesh}_contact", slab)
cylinder = {"steps": 100, "solver": {"dt": 0.01, "tolerance": 1e-4}, "gravity": [0, 0, -9.81],
            "bodies": [{"name": "cylinder", "mesh": "cylinder_8332.node",
                        "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3,
                                     "density": 1000, "stiffness_damping": 0.01},
                        "pose": {"position": [0, 0, 1.0],
                                 "axis_angle": {"axis": [1, 0, 0], "angle": 1.5707963267948966}}}]}
box = [{"name": "box", "shape": {"box": {"half_extents": [0.25, 0.25, 0.25]}}, "mass": 5,
        "pose": {"position": [0, 0, 2.3]}}]
ground = dict(cylinder, ground={"height": 0, "friction": 0.5})
write("cylinder_alone", dict(ground))
write("cylinder_contact", dict(ground, rigid_bodies=box))
# Lying along y after the pose: its end caps at y = 0 and y = -10.
caps = [{"name": n, "body": "cylinder", "select": {"plane": {"point": [0, y, 0], "normal": [0, 1, 0],
                                                             "tolerance": 1e-3}}}
        for n, y in (("near", 0), ("far", -10))]
held = dict(cylinder, node_sets=caps)
held["rigid_bodies"] = [dict(box[0], pose={"position": [0, -5, 2.3]})]
write("cylinder_held_contact", held)
write("cylinder_held_alone", dict(cylinder, node_sets=caps))
EOF

# ---- Runs ----
RAW=$OUT/raw.jsonl
: >"$RAW"
for case in slab_box slab_tetgen cylinder cylinder_held; do
  for variant in alone contact; do
    scene=$OUT/${case}_$variant.json
    for ((r = 0; r < REPS; ++r)); do
      "$T" run "$scene" --out "$OUT/run" --threads 1 >/dev/null
      python3 - "$OUT/run/summary.json" "$case" "$variant" >>"$RAW" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
c = s.get("contacts", {})
print(json.dumps({"engine": "torsion", "case": sys.argv[2], "variant": sys.argv[3],
                  "ms_median": s["ms_per_step"]["median"], "ms_p95": s["ms_per_step"]["p95"],
                  "cg_mean": s["solver_iterations"]["mean"], "stable": s["stable"],
                  "unconverged": c.get("unconverged_steps", 0)}))
EOF
    done
    if [[ $BULLET == 1 ]]; then
      "$BB" "$scene" --steps 100 | python3 -c "
import json, sys
for line in sys.stdin:
    j = json.loads(line)
    if j.get('engine') == 'bullet':
        print(json.dumps({'engine': 'bullet', 'case': '$case', 'variant': '$variant',
                          'ms_mean': 1000 / j['steps_per_second'] if j['steps_per_second'] else None,
                          'outcome': j.get('outcome'), 'error': j.get('error')}))" >>"$RAW"
    fi
  done
done
echo "load at end: $(cut -d' ' -f1-3 /proc/loadavg)" >>"$OUT/machine.txt"

# ---- Table ----
python3 - "$RAW" >"$OUT/summary.md" <<'EOF'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
print("| case | Torsion ms/step median (p95), alone | with contact | ratio of medians | CG/step alone, contact | Bullet ms/step alone | with contact | Bullet ratio |")
print("|---|---|---|---|---|---|---|---|")
for case in dict.fromkeys(r["case"] for r in rows):
    t = {v: [r for r in rows if r["case"] == case and r["variant"] == v and r["engine"] == "torsion"]
         for v in ("alone", "contact")}
    med = {v: statistics.median(r["ms_median"] for r in t[v]) for v in t}
    p95 = {v: statistics.median(r["ms_p95"] for r in t[v]) for v in t}
    cg = {v: t[v][0]["cg_mean"] for v in t}
    b = {v: [r for r in rows if r["case"] == case and r["variant"] == v and r["engine"] == "bullet"]
         for v in ("alone", "contact")}
    bm = {v: (b[v][0]["ms_mean"] if b[v] and b[v][0]["ms_mean"] else None) for v in b}
    fmt = lambda x: "-" if x is None else f"{x:.1f}"
    br = f"{bm['contact'] / bm['alone']:.2f}x" if bm["alone"] and bm["contact"] else "-"
    print(f"| {case} | {med['alone']:.1f} ({p95['alone']:.1f}) | {med['contact']:.1f} ({p95['contact']:.1f}) "
          f"| **{med['contact'] / med['alone']:.2f}x** | {cg['alone']:.1f}, {cg['contact']:.1f} "
          f"| {fmt(bm['alone'])} | {fmt(bm['contact'])} | {br} |")
EOF
cat "$OUT/machine.txt" "$OUT/summary.md"
