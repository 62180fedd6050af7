#!/usr/bin/env python3
"""Writes assets/doom3/, a small Doom 3-style mod folder of our own, for the Doom 3
readers and their tests: a humanoid .md5mesh (skeleton and a few hundred skinned
vertices), an af_pose and a walk .md5anim, its articulated figure (.af) and the .def
declarations that tie them together (an entityDef that inherits, and a model
declaration).

Conventions are Doom 3's: inches, Z up, the figure facing +X (left is +Y). md5 files
store a quaternion's x, y, z; Doom 3 completes w = +sqrt(1 - x^2 - y^2 - z^2) and applies
the conjugate of that quaternion to column vectors, so a rotation q = (v, s) with s >= 0
is written as -v.

Python 3 standard library only. Run from anywhere: python3 scripts/make_doom3_mod.py
"""

import math
import os

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "assets", "doom3")

# ---------------------------------------------------------------- quaternions (w, x, y, z)


def qmul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def qconj(q):
    return (q[0], -q[1], -q[2], -q[3])


def qaxis(axis, deg):
    x, y, z = axis
    n = math.sqrt(x * x + y * y + z * z)
    h = math.radians(deg) / 2
    s = math.sin(h) / n
    return (math.cos(h), x * s, y * s, z * s)


def qrot(q, v):
    p = qmul(qmul(q, (0.0, v[0], v[1], v[2])), qconj(q))
    return (p[1], p[2], p[3])


def file_xyz(q):
    """The md5 file's x, y, z for the column-vector rotation q (see the module docs)."""
    w, x, y, z = q
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    return (-x, -y, -z)


def add(a, b):
    return tuple(p + q for p, q in zip(a, b))


def sub(a, b):
    return tuple(p - q for p, q in zip(a, b))


def fmt(v):
    """Numbers as md5 files write them, without trailing zeros or a negative zero."""
    out = []
    for c in v:
        s = f"{c:.6f}".rstrip("0").rstrip(".")
        out.append("0" if s in ("-0", "0", "") else s)
    return " ".join(out)


# ---------------------------------------------------------------- skeleton

IDENT = (1.0, 0.0, 0.0, 0.0)
# name, parent, bind position (inches), bind rotation. Mixed case as id's meshes spell
# their joints ("Ruparm"); the .af below writes some of them in other cases, which
# Doom 3 accepts (joint names compare without regard to case).
JOINTS = [
    ("origin", -1, (0, 0, 0), IDENT),
    ("Body", 0, (0, 0, 38), IDENT),
    ("Waist", 1, (0, 0, 44), IDENT),
    ("Chest", 2, (0, 0, 52), IDENT),
    ("Neck", 3, (0, 0, 60), IDENT),
    ("Head", 4, (0, 0, 63), qaxis((0, 1, 0), -10)),
    ("Luparm", 3, (0, 10, 57), qaxis((1, 0, 0), 90)),
    ("Lloarm", 6, (0, 10, 45), qaxis((1, 0, 0), 90)),
    ("Lhand", 7, (0, 10, 34), qaxis((1, 0, 0), 90)),
    ("Ruparm", 3, (0, -10, 57), qaxis((1, 0, 0), -90)),
    ("Rloarm", 9, (0, -10, 45), qaxis((1, 0, 0), -90)),
    ("Rhand", 10, (0, -10, 34), qaxis((1, 0, 0), -90)),
    ("Lupleg", 1, (0, 4, 37), IDENT),
    ("Lloleg", 12, (0, 4, 19), IDENT),
    ("Lankle", 13, (0, 4, 2), IDENT),
    ("Rupleg", 1, (0, -4, 37), IDENT),
    ("Rloleg", 15, (0, -4, 19), IDENT),
    ("Rankle", 16, (0, -4, 2), IDENT),
    # Helper joints under the ankles on the ground, as id's skeletons carry "Lball" and
    # "Ltoe": the shin bodies reach down to them. Nothing is skinned to them.
    ("Lsole", 14, (0, 4, 0), IDENT),
    ("Rsole", 17, (0, -4, 0), IDENT),
]
INDEX = {j[0]: i for i, j in enumerate(JOINTS)}


def locals_from_model(model):
    """Parent-relative (t, q) from model-space (t, q): t_l = R_p^T (t - t_p), R_l = R_p^T R."""
    out = []
    for i, (name, parent, _, _) in enumerate(JOINTS):
        t, q = model[i]
        if parent < 0:
            out.append((t, q))
        else:
            tp, qp = model[parent]
            out.append((qrot(qconj(qp), sub(t, tp)), qmul(qconj(qp), q)))
    return out


def model_from_locals(loc):
    out = []
    for i, (name, parent, _, _) in enumerate(JOINTS):
        t, q = loc[i]
        if parent < 0:
            out.append((t, q))
        else:
            tp, qp = out[parent]
            out.append((add(tp, qrot(qp, t)), qmul(qp, q)))
    return out


BIND = [(tuple(float(c) for c in j[2]), j[3]) for j in JOINTS]
BIND_LOCAL = locals_from_model(BIND)

# ---------------------------------------------------------------- mesh

# Skin segments: (joint that carries it, start joint, end point joint or an offset in
# model space from the start, half-widths (across Y, across X)).
SEGMENTS = [
    ("Body", "Body", "Waist", (7, 4.5)),
    ("Waist", "Waist", "Chest", (7, 4)),
    ("Chest", "Chest", "Neck", (8, 4.5)),
    ("Neck", "Neck", "Head", (2, 2)),
    ("Head", "Head", (0, 0, 9), (3.5, 4)),
    ("Luparm", "Luparm", "Lloarm", (2, 2)),
    ("Lloarm", "Lloarm", "Lhand", (1.7, 1.7)),
    ("Lhand", "Lhand", (0, 0, -5), (1.5, 1)),
    ("Ruparm", "Ruparm", "Rloarm", (2, 2)),
    ("Rloarm", "Rloarm", "Rhand", (1.7, 1.7)),
    ("Rhand", "Rhand", (0, 0, -5), (1.5, 1)),
    ("Lupleg", "Lupleg", "Lloleg", (2.6, 2.6)),
    ("Lloleg", "Lloleg", "Lankle", (2.2, 2.2)),
    ("Lankle", "Lankle", (7, 0, 0), (1.8, 1.5)),
    ("Rupleg", "Rupleg", "Rloleg", (2.6, 2.6)),
    ("Rloleg", "Rloleg", "Rankle", (2.2, 2.2)),
    ("Rankle", "Rankle", (7, 0, 0), (1.8, 1.5)),
]
SIDES = 8
RINGS = 3


def build_mesh():
    """Vertices (uv, weights), triangles: an eight-sided tube with end caps per segment.

    Every vertex of a tube's middle and far rings hangs on the segment's own joint; its
    near ring on the own joint and the parent half and half, so weight ranges of one and
    two weights both occur. Offsets are in each joint's bind frame: o = R^T (p - t).
    """
    verts, tris = [], []
    for seg_i, (own, start, end, (wy, wx)) in enumerate(SEGMENTS):
        p0 = BIND[INDEX[start]][0]
        p1 = BIND[INDEX[end]][0] if isinstance(end, str) else add(p0, end)
        axis = sub(p1, p0)
        length = math.sqrt(sum(c * c for c in axis))
        d = tuple(c / length for c in axis)
        # Two directions across the segment.
        ref = (0, 0, 1) if abs(d[2]) < 0.9 else (1, 0, 0)
        u = (d[1] * ref[2] - d[2] * ref[1], d[2] * ref[0] - d[0] * ref[2], d[0] * ref[1] - d[1] * ref[0])
        un = math.sqrt(sum(c * c for c in u))
        u = tuple(c / un for c in u)
        v = (d[1] * u[2] - d[2] * u[1], d[2] * u[0] - d[0] * u[2], d[0] * u[1] - d[1] * u[0])
        parent = JOINTS[INDEX[own]][1]
        base = len(verts)
        for r in range(RINGS):
            f = r / (RINGS - 1)
            c = add(p0, tuple(a * f * length for a in d))
            for s in range(SIDES):
                a = 2 * math.pi * s / SIDES
                p = add(c, tuple(wy * math.cos(a) * uu + wx * math.sin(a) * vv for uu, vv in zip(u, v)))
                blend = r == 0 and parent > 0
                ws = [(INDEX[own], 0.5 if blend else 1.0)] + ([(parent, 0.5)] if blend else [])
                verts.append(((s / SIDES, f), p, ws))
        for r in range(RINGS - 1):
            for s in range(SIDES):
                a = base + r * SIDES + s
                b = base + r * SIDES + (s + 1) % SIDES
                c = a + SIDES
                e = b + SIDES
                # Clockwise as seen from outside: Doom 3's front faces.
                tris.append((a, b, c))
                tris.append((b, e, c))
        for r, centre in ((0, p0), (RINGS - 1, p1)):
            ci = len(verts)
            verts.append(((0.5, float(r)), centre, [(INDEX[own], 1.0)]))
            for s in range(SIDES):
                a = base + r * SIDES + s
                b = base + r * SIDES + (s + 1) % SIDES
                tris.append((ci, a, b) if r == 0 else (ci, b, a))
    return verts, tris


def write_md5mesh(path):
    verts, tris = build_mesh()
    lines = [
        "MD5Version 10",
        'commandline "written by scripts/make_doom3_mod.py"',
        "",
        f"numJoints {len(JOINTS)}",
        "numMeshes 1",
        "",
        "joints {",
    ]
    for (name, parent, _, _), (t, q) in zip(JOINTS, BIND):
        lines.append(f'\t"{name}"\t{parent} ( {fmt(t)} ) ( {fmt(file_xyz(q))} )')
    lines += ["}", "", "mesh {", "\t// meshes: lab_human", '\tshader "models/lab_human/skin"', ""]
    lines.append(f"\tnumverts {len(verts)}")
    weights = []
    for i, (uv, p, ws) in enumerate(verts):
        lines.append(f"\tvert {i} ( {fmt(uv)} ) {len(weights)} {len(ws)}")
        for j, bias in ws:
            t, q = BIND[j]
            weights.append((j, bias, qrot(qconj(q), sub(p, t))))
    lines += ["", f"\tnumtris {len(tris)}"]
    lines += [f"\ttri {i} {a} {b} {c}" for i, (a, b, c) in enumerate(tris)]
    lines += ["", f"\tnumweights {len(weights)}"]
    lines += [f"\tweight {i} {j} {fmt((b,))} ( {fmt(o)} )" for i, (j, b, o) in enumerate(weights)]
    lines += ["}", ""]
    write(path, lines)


# ---------------------------------------------------------------- animations


def write_md5anim(path, frames_local, frame_rate, animated):
    """frames_local: per frame, per joint parent-relative (t, q). `animated`: joint ->
    flags (Tx 1, Ty 2, Tz 4, Qx 8, Qy 16, Qz 32); the baseframe is the first frame."""
    base = frames_local[0]
    hierarchy, start = [], 0
    for i, (name, parent, _, _) in enumerate(JOINTS):
        flags = animated.get(name, 0)
        comment = JOINTS[parent][0] if parent >= 0 else ""
        hierarchy.append(f'\t"{name}"\t{parent} {flags} {start}\t// {comment}'.rstrip())
        start += bin(flags).count("1")
    lines = [
        "MD5Version 10",
        'commandline "written by scripts/make_doom3_mod.py"',
        "",
        f"numFrames {len(frames_local)}",
        f"numJoints {len(JOINTS)}",
        f"frameRate {frame_rate}",
        f"numAnimatedComponents {start}",
        "",
        "hierarchy {",
        *hierarchy,
        "}",
        "",
        "bounds {",
    ]
    for loc in frames_local:
        pts = [t for t, _ in model_from_locals(loc)]
        lo = tuple(min(p[k] for p in pts) - 4 for k in range(3))
        hi = tuple(max(p[k] for p in pts) + 4 for k in range(3))
        lines.append(f"\t( {fmt(lo)} ) ( {fmt(hi)} )")
    lines += ["}", "", "baseframe {"]
    for t, q in base:
        lines.append(f"\t( {fmt(t)} ) ( {fmt(file_xyz(q))} )")
    lines += ["}", ""]
    for k, loc in enumerate(frames_local):
        nums = []
        for i, (name, _, _, _) in enumerate(JOINTS):
            flags = animated.get(name, 0)
            t, q = loc[i]
            comps = list(t) + list(file_xyz(q))
            nums += [comps[b] for b in range(6) if flags & (1 << b)]
        lines += [f"frame {k} {{", "\t" + fmt(nums), "}", ""]
    write(path, lines)


def posed(turns, body_drop=0.0, forward=0.0):
    """Parent-relative joints of the bind pose with `turns` (joint -> (axis, degrees) in
    the parent's frame, applied after the bind rotation), the Body joint lowered and the
    origin joint moved `forward` along +X (root motion: Doom 3 moves the entity by it)."""
    loc = []
    for i, (name, _, _, _) in enumerate(JOINTS):
        t, q = BIND_LOCAL[i]
        if name in turns:
            axis, deg = turns[name]
            q = qmul(qaxis(axis, deg), q)
        if name == "Body":
            t = (t[0], t[1], t[2] - body_drop)
        if name == "origin":
            t = (t[0] + forward, t[1], t[2])
        loc.append((t, q))
    return loc


def af_pose():
    # Arms a little away from the sides (about the forward axis): the pose the
    # figure is built from, different from the bind pose.
    return [posed({"Luparm": ((1, 0, 0), 12), "Ruparm": ((1, 0, 0), -12)})]


# The walk: one cycle (two steps) a second, 24 frames at 24 fps. Each step is as long as
# the legs' swing reaches: 2 · 37 in · sin 25°, so the root moves 4 · 37 sin 25° a cycle
# (62.5 in, 1.59 m/s), forward along +X, the way the figure faces.
WALK_FRAMES = 24
WALK_RATE = 24
WALK_STRIDE = 4 * 37 * math.sin(math.radians(25))


def walk():
    frames = []
    n = WALK_FRAMES
    for k in range(n + 1):
        ph = 2 * math.pi * (k % n) / n
        s = math.sin(ph)
        # Legs and arms swing about the left axis (+Y): a turn of -a about +Y takes a
        # limb hanging along -Z forward (+X), since R_y(a) maps -Z to (-sin a, 0, -cos a).
        turns = {
            "Lupleg": ((0, 1, 0), -25 * s),
            "Rupleg": ((0, 1, 0), 25 * s),
            "Lloleg": ((0, 1, 0), 20 * max(0.0, -math.cos(ph))),
            "Rloleg": ((0, 1, 0), 20 * max(0.0, math.cos(ph))),
            "Luparm": ((0, 1, 0), 20 * s),
            "Ruparm": ((0, 1, 0), -20 * s),
        }
        frames.append(posed(turns, body_drop=1.0 - abs(math.cos(ph)), forward=WALK_STRIDE * k / n))
    return frames


# ---------------------------------------------------------------- .af and .def

AF = """/*
	Written by scripts/make_doom3_mod.py: a Doom 3-style 11-body humanoid in plain
	Doom 3 syntax. Inches, Z up, facing +X. Every vector is a joint reference into the
	model's skeleton, which Doom 3 (and ragdoll-lab) takes in the model's af_pose frame.
	Some joint names are written in another case than the mesh's ("RUPARM"), as id's
	own files do; Doom 3 compares them without regard to case.
	The left knee's limit starts 4 degrees outside its rest pose (like id's zombie
	knees); the shins end on the ground, at the sole joints.
	containedJoints name each body's joints for hits on the mesh; the sole joints
	come last in the skeleton, outside the run `*Lloleg` takes, so the shins name
	them as well.
	A hinge `limit c, w, s` lets body1 turn s - c +- w/2 degrees right-handed about
	the axis (Doom 3's cone is left turned -c, its shaft left turned -s): about +Y
	(left), the knees' 45 +- 41 and 40 +- 45 swing the feet back and the elbows'
	-40 +- 50 swing the hands forward, as a human's do.
	Densities differ per body, as in id's figures, so that each body carries a human
	segment's share of totalMass (Winter's anthropometric table: pelvis 14 %, thorax
	and abdomen 36 %, head 8 %, upper arm 2.8 %, forearm and hand 2.2 %, thigh 10 %,
	shank and foot 6.1 %): density = share / volume, the volume of a bone model being
	width^2 length / 8. One density for all would leave each shin under 2 % of the
	figure under a torso of 73 %.
*/

articulatedFigure lab_human {

settings {
	model "lab_human"
	skin "skins/lab_human_blue"
	friction 0.01, 0.01, 0.8, 0.5
	suspendSpeed 20, 30, 40, 60
	noMoveTime 1
	noMoveTranslation 10
	noMoveRotation 10
	minMoveTime -1
	maxMoveTime -1
	totalMass 70
	contents corpse
	clipMask solid, corpse
	selfCollision 1
}

body "waist" {
	joint "origin"
	mod orientation
	model box( ( -4, -7, -3.5 ), ( 4, 7, 3.5 ) )
	origin bonecenter( "Body", "Waist" )
	density 0.0126
	friction 0.01, 0.01, 0.8
	containedJoints "origin Body -*Lupleg -*Rupleg"
}

body "chest" {
	joint "Waist"
	mod orientation
	model box( ( -4, -8, -7 ), ( 4, 8, 6 ) )
	origin joint( "Chest" )
	density 0.015
	containedJoints "*Waist -*Neck -*Luparm -*Ruparm"
}

body "head" {
	joint "neck"
	mod orientation
	model box( ( -4, -3.5, 0 ), ( 4, 3.5, 9 ) )
	origin joint( "NECK" )
	density 0.0113
	containedJoints "*Neck"
}

body "luparm" {
	joint "Luparm"
	mod orientation
	model bone( joint( "luparm" ), joint( "Lloarm" ), 4 )
	density 0.082
	containedJoints "Luparm"
}

body "lloarm" {
	joint "Lloarm"
	mod orientation
	model bone( joint( "Lloarm" ), joint( "Lhand" ), 3.5 )
	density 0.092
	containedJoints "*Lloarm"
}

body "ruparm" {
	joint "Ruparm"
	mod orientation
	model bone( joint( "RUPARM" ), joint( "Rloarm" ), 4 )
	density 0.082
	containedJoints "Ruparm"
}

body "rloarm" {
	joint "Rloarm"
	mod orientation
	model bone( joint( "Rloarm" ), joint( "Rhand" ), 3.5 )
	density 0.092
	containedJoints "*Rloarm"
}

body "lupleg" {
	joint "Lupleg"
	mod orientation
	model bone( joint( "Lupleg" ), joint( "Lloleg" ), 5 )
	density 0.124
	containedJoints "Lupleg"
}

body "lloleg" {
	joint "Lloleg"
	mod orientation
	model bone( joint( "Lloleg" ), joint( "Lsole" ), 4.5 )
	density 0.089
	containedJoints "*Lloleg Lsole"
}

body "rupleg" {
	joint "Rupleg"
	mod orientation
	model bone( joint( "Rupleg" ), joint( "Rloleg" ), 5 )
	density 0.124
	containedJoints "Rupleg"
}

body "rloleg" {
	joint "Rloleg"
	mod orientation
	model bone( joint( "Rloleg" ), joint( "Rsole" ), 4.5 )
	density 0.089
	containedJoints "*Rloleg Rsole"
}

universalJoint "waist_chest" {
	body1 "chest"
	body2 "waist"
	anchor joint( "Waist" )
	shafts ( 0, 0, 1 ), ( 0, 0, -1 )
	friction 0.1
	conelimit ( 0, 0, 1 ), 60
}

ballAndSocketJoint "neck" {
	body1 "head"
	body2 "chest"
	anchor joint( "Neck" )
	friction 0.1
	conelimit ( 0, 0, 1 ), 80, ( 0, 0, 1 )
}

ballAndSocketJoint "l_shoulder" {
	body1 "luparm"
	body2 "chest"
	anchor joint( "Luparm" )
	friction 0.1
	pyramidlimit bonedir( "Luparm", "Lloarm" ), 150, 100, 0, bonedir( "Luparm", "Lloarm" )
}

ballAndSocketJoint "r_shoulder" {
	body1 "ruparm"
	body2 "chest"
	anchor joint( "Ruparm" )
	friction 0.1
	pyramidlimit bonedir( "Ruparm", "Rloarm" ), 150, 100, 0, bonedir( "Ruparm", "Rloarm" )
}

hinge "l_elbow" {
	body1 "lloarm"
	body2 "luparm"
	anchor joint( "Lloarm" )
	axis ( 0, 1, 0 )
	limit 40, 100, 0
	friction 0.05
}

hinge "r_elbow" {
	body1 "rloarm"
	body2 "ruparm"
	anchor joint( "Rloarm" )
	axis ( 0, 1, 0 )
	limit 40, 100, 0
	friction 0.05
}

universalJoint "l_hip" {
	body1 "lupleg"
	body2 "waist"
	anchor joint( "Lupleg" )
	shafts ( 0, 0, -1 ), ( 0, 0, 1 )
	friction 0.1
	pyramidlimit ( 0, 0, -1 ), 100, 50, 0
}

universalJoint "r_hip" {
	body1 "rupleg"
	body2 "waist"
	anchor joint( "Rupleg" )
	shafts ( 0, 0, -1 ), ( 0, 0, 1 )
	friction 0.1
	pyramidlimit ( 0, 0, -1 ), 100, 50, 0
}

hinge "l_knee" {
	body1 "lloleg"
	body2 "lupleg"
	anchor joint( "Lloleg" )
	axis ( 0, 1, 0 )
	limit 45, 82, 90
	friction 0.05
}

hinge "r_knee" {
	body1 "rloleg"
	body2 "rupleg"
	anchor joint( "Rloleg" )
	axis ( 0, 1, 0 )
	limit 50, 90, 90
	friction 0.05
}

}
"""

DEF = """/*
	Written by scripts/make_doom3_mod.py: the lab humanoid's declarations, as a
	monster's would be written. monster_lab_human inherits its figure from
	monster_lab_base.
*/

model lab_human {
	mesh	models/md5/lab_human/lab_human.md5mesh
	skin	skins/lab_human_blue
	channel torso ( *Waist )
	channel legs ( origin Body *Lupleg *Rupleg )

	anim af_pose	models/md5/lab_human/af_pose.md5anim
	anim walk	models/md5/lab_human/walk.md5anim {
		frame 1 footstep
		frame 5 footstep
	}
}

entityDef monster_lab_base {
	"editor_usage"	"Base of the lab's humanoids: its ragdoll."
	"ragdoll"	"lab_human"
	"velocityTime"	"0"
}

entityDef monster_lab_human {
	"inherit"	"monster_lab_base"
	"editor_usage"	"The lab's humanoid: mesh, af_pose and walk from model lab_human."
	"model"	"lab_human"
	"skin"	"skins/lab_human_red"
}
"""


def write(path, lines):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    text = "\n".join(lines) if isinstance(lines, list) else lines
    with open(path, "w", newline="\n") as f:
        f.write(text)


def main():
    md5 = os.path.join(ROOT, "models", "md5", "lab_human")
    write_md5mesh(os.path.join(md5, "lab_human.md5mesh"))
    rot = 8 | 16 | 32
    write_md5anim(os.path.join(md5, "af_pose.md5anim"), af_pose(), 24, {"Luparm": rot, "Ruparm": rot})
    write_md5anim(
        os.path.join(md5, "walk.md5anim"),
        walk(),
        WALK_RATE,
        {"origin": 1, "Body": 4, "Lupleg": rot, "Rupleg": rot, "Lloleg": rot, "Rloleg": rot, "Luparm": rot, "Ruparm": rot},
    )
    write(os.path.join(ROOT, "af", "lab_human.af"), AF)
    write(os.path.join(ROOT, "def", "lab_human.def"), DEF)


if __name__ == "__main__":
    main()
