#!/usr/bin/env python3
"""Writes the results tables: `ragdoll-lab stats` over scenes 1-9 and their variants,
10 simulated seconds each, for the particle method's rigid-frames solver (the default),
its paper solver, its XPBD solver and the multibody method. The metrics are defined in docs/metrics.md.

The tables replace what stands between the marker lines
`<!-- results:begin -->` and `<!-- results:end -->` in docs/results.md and README.md
(the markers stay). With --print they are printed instead and no file is touched.

Usage: scripts/results.py [path/to/ragdoll-lab] [--print]
"""
import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
TARGETS = [ROOT / "docs" / "results.md", ROOT / "README.md"]
BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"

SCENES = [(1, 1), (2, 1), (2, 2), (3, 1), (3, 2), (3, 3), (4, 1), (4, 2),
          (5, 1), (6, 1), (7, 1), (8, 1), (9, 1)]
RUNS = [("particle, rigid frames (default)",
         ["--method", "particle", "--particle-solver", "rigid-frames"], "particle"),
        ("particle, paper", ["--method", "particle", "--particle-solver", "paper"], "particle"),
        ("particle, xpbd", ["--method", "particle", "--particle-solver", "xpbd"], "particle"),
        ("multibody", ["--method", "multibody"], "multibody")]
HEADER = ("| scene | variant | energy gain | energy lost | max speed (m/s) | max penetration (m) "
          "| max joint gap (m) | max limit violation (°) | max stretch | asleep at (s) | ms/step |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|")


def fmt(v, f):
    return "—" if v is None else f.format(v)


def row(binary, scene, variant, args, key):
    out = subprocess.run([binary, "stats", "--scene", str(scene), "--variant", str(variant),
                          "--seconds", "10", *args], check=True, capture_output=True, text=True)
    d = json.loads(out.stdout)
    m = d["methods"][key]
    return (f"| {scene} {d['scene']} | {variant} | {fmt(m['energy_gain'], '{:.4f}')} "
            f"| {fmt(m['energy_loss'], '{:.4f}')} | {fmt(m['max_body_speed_mps'], '{:.2f}')} "
            f"| {fmt(m['max_penetration_m'], '{:.4f}')} | {fmt(m['max_joint_gap_m'], '{:.4f}')} "
            f"| {fmt(m['max_limit_violation_deg'], '{:.2f}')} "
            f"| {fmt(m['max_bone_stretch'], '{:.4f}')} "
            f"| {fmt(m['asleep_at_s'], '{:.2f}')} | {fmt(m['step_ms_mean'], '{:.3f}')} |"
            + ("" if m["finite"] else " **not finite**"))


def tables(binary):
    parts = []
    for title, args, key in RUNS:
        print(f"results: {title}", file=sys.stderr)
        rows = [row(binary, s, v, args, key) for s, v in SCENES]
        parts.append(f"**{title}**\n\n{HEADER}\n" + "\n".join(rows))
    return "\n\n".join(parts)


def replace_between_markers(path, body, markers=(BEGIN, END), who="results"):
    """Replaces what stands between the two marker lines of `path` by `body`."""
    begin, end = markers
    text = path.read_text()
    start, stop = text.find(begin), text.find(end)
    if start < 0 or stop < start:
        sys.exit(f"error: {path}: no `{begin}` ... `{end}` markers")
    path.write_text(text[:start + len(begin)] + "\n\n" + body + "\n\n" + text[stop:])
    print(f"{who}: wrote {path.relative_to(ROOT)}", file=sys.stderr)


def main():
    args = [a for a in sys.argv[1:] if a != "--print"]
    binary = args[0] if args else str(ROOT / "target" / "release" / "ragdoll-lab")
    body = tables(binary)
    if "--print" in sys.argv[1:]:
        print(body)
        return
    for path in TARGETS:
        replace_between_markers(path, body)


if __name__ == "__main__":
    main()
