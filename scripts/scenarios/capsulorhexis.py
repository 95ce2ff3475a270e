#!/usr/bin/env python3
"""Writes a capsulorhexis scenario derived from data/scenarios/capsulorhexis_demo.json
(scripts/scenarios/make_all.sh writes the expert and novice drills with it).

usage: capsulorhexis.py OUT.json [--scale F] [--shift DX,DY] [--outward T0,T1,G] [--regrasp R]
                         --name N --description D

--scale   scales both hands' tracks about the optical axis (the opening's size follows);
--shift   moves them sideways, mm (an off-centre rhexis);
--outward pulls the forceps outward between T0 and T1 s, the radius growing to (1 + G) times
          (a tear that runs out radially);
--regrasp the radius (mm, before --scale) at which the forceps take the flap again after each
          quarter; the demo's 2.3 mm, 0.3 mm inside the circle, is the flap's middle, and on the
          coarse meshes the pull reached the tear's tip so weakly there that the last quarter's
          tear closed or stopped on rounding (docs/cutting_and_tearing.md, "Closing"); the
          default 2.4 mm takes the flap nearer the tear, as the first grasp does.
Every point near the capsule keeps its height above the anterior lens surface (DESIGN.md §6).
Then each hand pivots in its corneal port (scripts/scenarios/ports.py): the forceps' (left hand)
shaft passes through the side port's centre, the cystotome's (right hand) through the main
port's, whenever the tip is inside the eye; the tips' paths are the ones above.
"""
import argparse, json, math, os, re
import ports

A, R = 1.8, 4.7  # anterior half-thickness and equatorial radius of the standard lens, mm


def surface_z(r):
    return A * math.sqrt(max(0.0, 1 - (r / R) ** 2))


def move(p, f=1.0, dx=0.0, dy=0.0):
    x, y, z = p["pos"]
    x2, y2 = x * f + dx, y * f + dy
    if z < 2.6:  # near the capsule: keep the height above the surface
        z = z - surface_z(math.hypot(x, y)) + surface_z(math.hypot(x2, y2))
    p["pos"] = [round(x2, 4), round(y2, 4), round(z, 4)]


ap = argparse.ArgumentParser()
ap.add_argument("out")
ap.add_argument("--scale", type=float, default=1.0)
ap.add_argument("--shift", default="0,0")
ap.add_argument("--outward", default=None)
ap.add_argument("--regrasp", type=float, default=2.4)
ap.add_argument("--name", required=True)
ap.add_argument("--description", required=True)
args = ap.parse_args()
demo = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "data", "scenarios", "capsulorhexis_demo.json")
s = json.load(open(demo))
dx, dy = (float(v) for v in args.shift.split(","))
DEMO_REGRASP_MM = 2.3  # the demo's regrasps (scenarios/capsulorhexis_demo.json)
for p in s["hands"]["left"]["track"]:
    if abs(math.hypot(p["pos"][0], p["pos"][1]) - DEMO_REGRASP_MM) < 1e-6:
        move(p, args.regrasp / DEMO_REGRASP_MM)
for hand in s["hands"].values():
    for p in hand["track"]:
        move(p, args.scale, dx, dy)
if args.outward:
    t0, t1, g = (float(v) for v in args.outward.split(","))
    for p in s["hands"]["left"]["track"]:
        if t0 <= p["t"] <= t1:
            move(p, 1 + g * (p["t"] - t0) / (t1 - t0))
port_of = {"left": "side", "right": "main"}
centres = ports.default_ports(s["drill"])
for name, hand in s["hands"].items():
    centre, axis = centres[port_of[name]]
    hand["track"] = ports.pivot_track(hand["track"], centre, axis, ports.inside_eye(),
                                      bend=ports.BEND_MM.get(hand["tool"], 0.0))
s["name"], s["description"] = args.name, args.description
text = json.dumps(s, indent=2)
# one sample per line, as the other scenarios
text = re.sub(r'\{\s+"t": ([^{}]*?)\s+\}', lambda m: '{ "t": ' + re.sub(r"\s+", " ", m.group(1)) + " }", text)
text = re.sub(r"\[\s+([-\d.e, \s]+?)\s+\]", lambda m: "[" + re.sub(r"\s+", " ", m.group(1)) + "]", text)
open(args.out, "w").write(text + "\n")
