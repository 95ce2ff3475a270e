#!/usr/bin/env python3
"""Writes a scripted corneal-incision scenario: one straight keratome pass.

usage: incision.py OUT.json [--hour 3] [--limbus 0.5] [--angle 28] [--name N] [--description D]

The keratome (right hand) starts 0.5 mm above the anterior corneal surface, at the clock hour
(12 = +y, 3 = +x) and the distance inside the limbus given, its blade in the meridional plane
tilted `angle` degrees below the surface's tangent plane (the angle that sets the tunnel length:
about limbal thickness / sin angle). It advances straight along its axis until its shoulders are
2.1 mm past the posterior surface (full width on both surfaces), pauses, and withdraws along the
same line. Deterministic; the eye is data/eye/standard_eye.json's (DESIGN.md §6 frame, mm).
The keratome does not pivot in a port (scripts/scenarios/ports.py): it is cutting the main port,
and the tool-eye ports leave it out (docs/tool_eye_interaction.md).
"""
import argparse, json, math

ap = argparse.ArgumentParser()
ap.add_argument("out")
ap.add_argument("--hour", type=float, default=3.0)
ap.add_argument("--limbus", type=float, default=0.5, help="mm inside the limbus")
ap.add_argument("--angle", type=float, default=28.0, help="degrees below the corneal surface")
ap.add_argument("--name", default="corneal incision expert")
ap.add_argument("--description", default="")
args = ap.parse_args()

# standard_eye.json: anterior radius 7.8, posterior radius 6.5, posterior apex z 4.8, central
# thickness 0.53, limbus diameter 11.6; spheres centred on the optical axis.
RA, RP, LIMBUS = 7.8, 6.5, 5.8
CA = 4.8 + 0.53 - RA
CP = 4.8 - RP
SHOULDER = 1.5  # KeratomeShape::shoulder_mm


def sub(a, b): return [a[i] - b[i] for i in range(3)]
def add(a, b): return [a[i] + b[i] for i in range(3)]
def mul(s, a): return [s * v for v in a]
def dot(a, b): return sum(a[i] * b[i] for i in range(3))
def cross(a, b): return [a[1]*b[2] - a[2]*b[1], a[2]*b[0] - a[0]*b[2], a[0]*b[1] - a[1]*b[0]]
def unit(a): n = math.sqrt(dot(a, a)); return mul(1 / n, a)


theta = args.hour / 12 * 2 * math.pi
radial = [math.sin(theta), math.cos(theta), 0.0]
r = LIMBUS - args.limbus
entry = add(mul(r, radial), [0, 0, CA + math.sqrt(RA * RA - r * r)])
n = unit(sub(entry, [0, 0, CA]))                 # outward normal of the anterior surface
t = unit(sub([0, 0, 1], mul(dot([0, 0, 1], n), n)))  # tangent toward the apex (meridional plane)
a = math.radians(args.angle)
d = add(mul(math.cos(a), t), mul(-math.sin(a), n))  # blade axis: into the stroma
lateral = unit(cross([-radial[0], -radial[1], 0.0], [0, 0, 1]))  # along the limbus (keratome.hpp)

# Where the axis meets the posterior sphere (first crossing): the tunnel's inner end.
c = sub(entry, [0, 0, CP])
b = dot(c, d)
disc = b * b - (dot(c, c) - RP * RP)
if disc < 0:
    raise SystemExit("incision.py: the blade never reaches the posterior surface at this angle")
tunnel = -b - math.sqrt(disc) if dot(c, c) > RP * RP else -b + math.sqrt(disc)


def quat(dv, lv):
    # Tool frame: columns (d × l, l, −d) (systems/incision/keratome.cpp tool_quat_for_blade).
    x = cross(dv, lv); y = lv; z = mul(-1, dv)
    m = [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1) * 2
        q = [s / 4, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s]
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1 + m[0][0] - m[1][1] - m[2][2]) * 2
        q = [(m[2][1] - m[1][2]) / s, s / 4, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s]
    elif m[1][1] > m[2][2]:
        s = math.sqrt(1 + m[1][1] - m[0][0] - m[2][2]) * 2
        q = [(m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, s / 4, (m[1][2] + m[2][1]) / s]
    else:
        s = math.sqrt(1 + m[2][2] - m[0][0] - m[1][1]) * 2
        q = [(m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, s / 4]
    return [round(v, 6) + 0.0 for v in q]


q = quat(d, lateral)
start = add(entry, mul(-0.5, d))
deepest = add(entry, mul(tunnel + SHOULDER + 0.6, d))
track = []
def key(time, pos):
    track.append({"t": round(time, 3), "pos": [round(v, 4) + 0.0 for v in pos], "quat": q})
key(0.0, start)
key(0.3, start)                       # settle on the limbus
advance = tunnel + SHOULDER + 1.1     # mm from start to deepest
key(0.3 + advance / 3.0, deepest)     # 3 mm/s through the stroma into the chamber
key(0.5 + advance / 3.0, deepest)     # pause
key(1.1 + advance / 3.0, start)       # withdraw along the tunnel
duration = round(1.3 + advance / 3.0, 3)
key(duration, start)

sc = {
    "name": args.name,
    "description": args.description,
    "drill": "corneal_incision",
    "eye": {"level": 3},
    "dt_s": 1 / 120,
    "seed": 2,
    "duration_s": duration,
    "hands": {"right": {"tool": "keratome", "track": track}},
}
with open(args.out, "w") as f:
    json.dump(sc, f, indent=2)
    f.write("\n")
