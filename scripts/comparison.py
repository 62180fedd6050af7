#!/usr/bin/env python3
"""Writes the side-by-side comparison: the three particle solvers (paper, rigid frames,
XPBD) and the multibody method, one column each, on quality and on cost.

Quality: scenes 1-9 (variant 1, 10 simulated seconds, `ragdoll-lab stats`) held to the
bounds of docs/results.md ("Quality bounds"), the worst figure of each metric over those
scenes, and the closed-form suite (`cargo test --release -p ragdoll-sim --test
closed_forms -- --include-ignored`, run once, counted per solver module).
Cost: µs per awake body per step in the moving pile with sleeping off, one thread
(`ragdoll-lab bench scale --only 10,100 --no-sleep --json --particle-solver S`; each run
times the multibody beside, whose column shows the median of the three runs), how that
figure grows from 10 to 100 humans, and bytes per bone (`ragdoll-lab bench memory
--only 4096 --json`: the jointless stack of 4096 boxes and the pile of 1000
humans).

The table replaces what stands between `<!-- comparison:begin -->` and
`<!-- comparison:end -->` in README.md (the markers stay). With --print it is printed
instead and no file is touched.

Usage: scripts/comparison.py [path/to/ragdoll-lab] [--print]
"""
import json
import pathlib
import re
import statistics
import subprocess
import sys
import time

from results import replace_between_markers

ROOT = pathlib.Path(__file__).resolve().parent.parent
TARGET = ROOT / "README.md"
BEGIN, END = "<!-- comparison:begin -->", "<!-- comparison:end -->"

SCENES = range(1, 10)
SCALE_HUMANS = (10, 100)
STACK_BONES = 4096
PILE_HUMANS = 1000

# (column title, `stats` arguments, `stats` method key, closed-form module,
#  `bench --particle-solver` value, `bench memory` key, bounds)
# The bounds are those of docs/results.md, "Quality bounds": the particle column (which the
# XPBD solver is held to as well, and against which the paper solver is read) and the
# multibody column; `asleep` lists the scenes that must fall asleep.
PARTICLE_BOUNDS = {"energy_gain": 0.02, "max_penetration_m": 0.01, "max_joint_gap_m": 0.005,
                   "max_limit_violation_deg": 3.0, "max_bone_stretch": 0.01,
                   "final_kinetic": 0.001, "asleep": (7, 8)}
MULTIBODY_BOUNDS = {"energy_gain": 0.02, "max_penetration_m": 0.01, "max_joint_gap_m": 0.002,
                    "max_limit_violation_deg": 2.0, "asleep": (7, 8, 9)}
SOLVERS = [
    ("particle, paper", ["--method", "particle", "--particle-solver", "paper"], "particle",
     None, "paper", "particle_paper", PARTICLE_BOUNDS),
    ("particle, rigid frames", ["--method", "particle", "--particle-solver", "rigid-frames"],
     "particle", "rigid_frames", "rigid-frames", "particle_rigid_frames", PARTICLE_BOUNDS),
    ("particle, XPBD", ["--method", "particle", "--particle-solver", "xpbd"], "particle",
     "xpbd", "xpbd", "particle_xpbd", PARTICLE_BOUNDS),
    ("multibody", ["--method", "multibody"], "multibody", "multibody", None, "multibody",
     MULTIBODY_BOUNDS),
]
DASH = "—"


def log(msg):
    print(f"comparison: {msg}", file=sys.stderr)


def run_json(cmd):
    out = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def within(scene, m, bounds):
    """Whether one scene's metrics hold every bound."""
    if not m["finite"]:
        return False
    for key, bound in bounds.items():
        if key in ("asleep", "final_kinetic"):
            continue
        if m.get(key) is not None and m[key] > bound:
            return False
    if scene in bounds["asleep"]:
        if m["asleep_at_s"] is None:
            return False
        if "final_kinetic" in bounds and m["final_kinetic"] > bounds["final_kinetic"]:
            return False
    return True


def quality(binary, args, key, bounds):
    """Scenes held and the worst of each metric, with its scene, over scenes 1-9."""
    held, worst = 0, {}
    for scene in SCENES:
        d = run_json([binary, "stats", "--scene", str(scene), "--variant", "1",
                      "--seconds", "10", *args])
        m = d["methods"][key]
        held += within(scene, m, bounds)
        for metric in ("energy_gain", "max_penetration_m", "max_joint_gap_m",
                       "max_limit_violation_deg", "max_bone_stretch"):
            v = m.get(metric)
            if v is not None and (metric not in worst or v > worst[metric][0]):
                worst[metric] = (v, scene)
    return held, worst


def closed_forms():
    """Passed and listed closed-form properties per solver module, from one test run."""
    log("closed forms: cargo test --release -p ragdoll-sim --test closed_forms")
    out = subprocess.run(["cargo", "test", "--release", "-p", "ragdoll-sim", "--test",
                          "closed_forms", "--", "--include-ignored"],
                         cwd=ROOT, capture_output=True, text=True)
    counts = {}
    for module, result in re.findall(r"^test (\w+)::\w+ \.\.\. (\w+)$", out.stdout, re.M):
        passed, total = counts.get(module, (0, 0))
        counts[module] = (passed + (result == "ok"), total + 1)
    if not counts:
        sys.exit("error: the closed-form suite printed no test results:\n" + out.stderr)
    return counts


def scale(binary, solver):
    """µs per awake body-step, one thread, sleeping off, per row: particle and multibody."""
    humans = ",".join(str(n) for n in SCALE_HUMANS)
    d = run_json([binary, "bench", "scale", "--only", humans, "--no-sleep", "--json",
                  "--particle-solver", solver])
    particle, multibody = {}, {}
    for row in d["rows"]:
        if row["threads"] != 1:
            continue
        particle[row["humans"]] = row["particle_busy"]["us_per_awake_body_step"]
        multibody[row["humans"]] = row["multibody_busy"]["us_per_awake_body_step"]
    return particle, multibody


def memory(binary):
    """Bytes per bone per `bench memory` key: (stack of STACK_BONES, pile of PILE_HUMANS)."""
    d = run_json([binary, "bench", "memory", "--only", f"{STACK_BONES},{PILE_HUMANS}", "--json"])
    stack = next(r for r in d["rows"] if r["bones"] == STACK_BONES)
    pile = next(r for r in d["pile_rows"] if r["humans"] == PILE_HUMANS)
    def per_bone(row, k):
        return row[k]["bytes_per_bone"] if isinstance(row.get(k), dict) else None
    keys = {k for row in (stack, pile) for k, v in row.items() if isinstance(v, dict)}
    return {k: (per_bone(stack, k), per_bone(pile, k)) for k in keys}


def fmt(v, f):
    return DASH if v is None else f.format(v)


def worst_cell(worst, metric, f, scale_by=1.0):
    if metric not in worst:
        return DASH
    v, scene = worst[metric]
    return f"{f.format(v * scale_by)} ({scene})"


def table(binary):
    start = time.monotonic()
    cols = []
    for title, args, key, _, _, _, bounds in SOLVERS:
        log(f"scenes 1-9: {title}")
        cols.append(quality(binary, args, key, bounds))
    cf = closed_forms()
    log("memory")
    mem = memory(binary)
    busy, mb_busy = {}, {n: [] for n in SCALE_HUMANS}
    for _, _, _, _, solver, _, _ in SOLVERS:
        if solver is None:
            continue
        log(f"scale: {solver}")
        particle, multibody = scale(binary, solver)
        busy[solver] = particle
        for n in SCALE_HUMANS:
            mb_busy[n].append(multibody[n])
    busy_cols = []
    for _, _, _, _, solver, _, _ in SOLVERS:
        if solver is None:
            busy_cols.append({n: statistics.median(mb_busy[n]) for n in SCALE_HUMANS})
        else:
            busy_cols.append(busy[solver])

    n_lo, n_hi = SCALE_HUMANS
    rows = [
        ("scenes 1–9 within every bound", [f"{held} of {len(SCENES)}" for held, _ in cols]),
        ("worst energy gain (scene)",
         [worst_cell(w, "energy_gain", "{:.4f}") for _, w in cols]),
        ("worst penetration, mm (scene)",
         [worst_cell(w, "max_penetration_m", "{:.1f}", 1e3) for _, w in cols]),
        ("worst joint gap, mm (scene)",
         [worst_cell(w, "max_joint_gap_m", "{:.1f}", 1e3) for _, w in cols]),
        ("worst limit excess, ° (scene)",
         [worst_cell(w, "max_limit_violation_deg", "{:.2f}") for _, w in cols]),
        ("worst bone stretch (scene)",
         [worst_cell(w, "max_bone_stretch", "{:.4f}") for _, w in cols]),
        ("closed-form properties passed",
         [DASH if module is None else f"{cf[module][0]} of {cf[module][1]}"
          for _, _, _, module, _, _, _ in SOLVERS]),
        (f"µs per awake body-step, {n_lo}-human pile, sleeping off",
         [fmt(b.get(n_lo), "{:.2f}") for b in busy_cols]),
        (f"µs per awake body-step, {n_hi}-human pile, sleeping off",
         [fmt(b.get(n_hi), "{:.2f}") for b in busy_cols]),
        (f"growth of that figure, {n_lo} → {n_hi} humans",
         [DASH if b.get(n_lo) is None or b.get(n_hi) is None
          else f"{b[n_hi] / b[n_lo]:.2f}×" for b in busy_cols]),
        (f"memory, B per bone: jointless stack of {STACK_BONES} boxes",
         [fmt(mem.get(mkey, (None, None))[0], "{:.0f}") for _, _, _, _, _, mkey, _ in SOLVERS]),
        (f"memory, B per bone: pile of {PILE_HUMANS} humans after 90 frames",
         [fmt(mem.get(mkey, (None, None))[1], "{:.0f}") for _, _, _, _, _, mkey, _ in SOLVERS]),
    ]
    head = "| | " + " | ".join(title for title, *_ in SOLVERS) + " |\n"
    head += "|---|" + "---:|" * len(SOLVERS)
    body = "\n".join(f"| {name} | " + " | ".join(cells) + " |" for name, cells in rows)
    log(f"done in {time.monotonic() - start:.0f} s")
    return head + "\n" + body


def main():
    args = [a for a in sys.argv[1:] if a != "--print"]
    binary = args[0] if args else str(ROOT / "target" / "release" / "ragdoll-lab")
    body = table(binary)
    if "--print" in sys.argv[1:]:
        print(body)
        return
    replace_between_markers(TARGET, body, (BEGIN, END), "comparison")


if __name__ == "__main__":
    main()
