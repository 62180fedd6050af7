#!/usr/bin/env python3
"""Prints the README's results tables: `ragdoll-lab stats` over scenes 1-9 and their
variants, 10 simulated seconds, for the improved particle solver, the paper's particle
solver and the multibody solver. Usage: scripts/results.py [path/to/ragdoll-lab]"""
import json, subprocess, sys

BIN = sys.argv[1] if len(sys.argv) > 1 else "target/release/ragdoll-lab"
SCENES = [(1, 1), (2, 1), (2, 2), (3, 1), (3, 2), (3, 3), (4, 1), (4, 2),
          (5, 1), (6, 1), (7, 1), (8, 1), (9, 1)]
RUNS = [("particle, rigid frames (default)", ["--method", "particle", "--particle-solver", "rigid-frames"], "particle"),
        ("particle, paper", ["--method", "particle", "--particle-solver", "paper"], "particle"),
        ("multibody", ["--method", "multibody"], "multibody")]


def fmt(v, f):
    return "—" if v is None else f.format(v)


for title, args, key in RUNS:
    print(f"\n**{title}**\n")
    print("| scene | variant | energy gain | energy lost | max speed (m/s) | max penetration (m) "
          "| max joint gap (m) | max limit violation (°) | max stretch | asleep at (s) | ms/step |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for scene, variant in SCENES:
        out = subprocess.run([BIN, "stats", "--scene", str(scene), "--variant", str(variant),
                              "--seconds", "10", *args], check=True, capture_output=True, text=True)
        d = json.loads(out.stdout)
        m = d["methods"][key]
        print(f"| {scene} {d['scene']} | {variant} | {fmt(m['energy_gain'], '{:.4f}')} "
              f"| {fmt(m['energy_loss'], '{:.4f}')} | {fmt(m['max_body_speed_mps'], '{:.2f}')} "
              f"| {fmt(m['max_penetration_m'], '{:.4f}')} | {fmt(m['max_joint_gap_m'], '{:.4f}')} "
              f"| {fmt(m['max_limit_violation_deg'], '{:.2f}')} | {fmt(m['max_bone_stretch'], '{:.4f}')} "
              f"| {fmt(m['asleep_at_s'], '{:.2f}')} | {fmt(m['step_ms_mean'], '{:.3f}')} |"
              + ("" if m["finite"] else " **not finite**"))
