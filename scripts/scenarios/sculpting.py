#!/usr/bin/env python3
"""Writes a scripted divide-and-conquer scenario (phaco sculpting).

usage: sculpting.py OUT.json [--passes 0.4,1.15,1.9,2.65] [--lanes -0.35,0.35] [--name N] [--description D]

The phaco probe enters through the temporal incision, sculpts a trench in passes of increasing
depth (mm below the anterior lens surface at the centre), one pass per lane, turns the nucleus a
quarter turn with the tip in the trench (pedal 1) and sculpts the second trench the same way.
The defaults are the expert's (make_all.sh). The first pass shaves the surface, 0.4 mm down, so the
trench is an open groove in the microscope view (issue 19); data/scenarios/phaco_sculpting_demo.json
is the older roofed trench (--passes 0.8,1.5,2.2,2.65: its top layer stays). The probe pivots in the
main corneal port (scripts/scenarios/ports.py): its shaft passes through the port's centre in
every sample, and it rests 0.25 mm inside that centre on the tunnel's axis.
"""
import argparse, json, math
import ports
ap = argparse.ArgumentParser()
ap.add_argument("out")
ap.add_argument("--passes", default="0.4,1.15,1.9,2.65")
ap.add_argument("--lanes", default="-0.35,0.35")
ap.add_argument("--name", default="phaco sculpting demo")
ap.add_argument("--description", default="Divide and conquer: the phaco probe through the temporal incision sculpts a trench in four passes of increasing depth, two lanes each (pedal 3), rotates the nucleus a quarter turn with the tip in the trench (pedal 1), and sculpts the second trench the same way.")
args = ap.parse_args()
A, C = 4.7, 1.8          # lens equatorial radius, anterior half-thickness
port, axis = ports.default_ports("phaco_sculpting")["main"]  # temporal incision, 3 o'clock
rest = [round(port[i] + 0.25 * axis[i], 4) for i in range(3)]  # in the tunnel, on its axis
def lens_top(x, y):
    s = 1 - (x*x + y*y) / (A*A)
    return C * math.sqrt(max(s, 0))
def quat_for(tip):
    d = [port[i] - tip[i] for i in range(3)]
    n = math.sqrt(sum(v*v for v in d)); d = [v/n for v in d]
    # rotation taking +z onto d: axis z×d, angle acos(d_z)
    ax = (-d[1], d[0], 0.0); s = math.sqrt(ax[0]**2 + ax[1]**2)
    ang = math.acos(max(-1, min(1, d[2])))
    if s < 1e-12: return [1, 0, 0, 0]
    ax = [v/s for v in ax]
    h = ang/2
    return [round(math.cos(h), 6), round(ax[0]*math.sin(h), 6) + 0.0, round(ax[1]*math.sin(h), 6) + 0.0, 0]
track = []
t = 0.0
def add(dt, pos, pedal):
    global t
    t += dt
    pos = [round(v, 4) for v in pos]
    track.append({"t": round(t, 3), "pos": pos, "quat": quat_for(pos), "pedal": pedal})
track.append({"t": 0.0, "pos": rest, "quat": quat_for(rest), "pedal": 0})
def trench_pass(depth, y):
    # above the near end, down with irrigation, sculpt away from the incision, lift, come back
    x0, x1 = 2.3, -2.3
    add(0.5, (x0, y, 2.3), 1)
    add(0.3, (x0, y, lens_top(x0, y) - depth * 0.6), 2)
    n = 10
    for k in range(n + 1):
        x = x0 + (x1 - x0) * k / n
        add(2.0 / n if k else 0.2, (x, y, lens_top(x, y) - depth * (1 - 0.4 * (x / 2.3) ** 2)), 3)
    add(0.3, (x1, y, 2.3), 1)
# Four passes of increasing depth, each in two lanes 0.7 mm apart: a trench about 1.6 mm wide
# (1.5-2 tip diameters) and 80 % of the nucleus deep at the centre. The first pass takes the top
# layer off (0.4 mm down: the tip's sphere reaches the surface), so the groove is open.
passes = [float(v) for v in args.passes.split(",")]
lanes = [float(v) for v in args.lanes.split(",")]
def trench():
    for d in passes:
        for y in lanes: trench_pass(d, y)
trench()
# Rotation: pedal 1 (no ultrasound), the tip in the first trench at 1.5 mm from the axis, pushed
# round the axis a quarter turn and 0.22 rad more: the tip first crosses the trench's free play
# (about 0.35 mm at the tip's height, 13 deg at 1.5 mm), then pushes its wall (a kinematic
# contact, systems/nucleus/rotation.hpp).
r, z = 1.5, 0.4
add(0.6, (-r, 0, 2.3), 1)
add(0.4, (-r, 0, z), 1)
n = 12
for k in range(1, n + 1):
    a = math.pi + (math.pi / 2 + 0.22) * k / n
    add(2.0 / n, (r * math.cos(a), r * math.sin(a), z), 1)
add(0.4, (r * math.cos(a), r * math.sin(a), 2.3), 1)
trench()
add(0.8, rest, 0)
# Between the samples the engine interpolates (lerp, slerp): extra samples keep the shaft on the
# port's centre there too.
track = ports.pivot_track(track, port, axis, ports.inside_eye())
sc = {
  "name": args.name,
  "description": args.description,
  "drill": "phaco_sculpting",
  "eye": {"level": 3},
  "dt_s": 1/120,
  "seed": 3,
  "duration_s": round(t, 3),
  "hands": {"right": {"tool": "phaco_probe", "track": track}}
}
s = json.dumps(sc, indent=2)
# one sample per line, as the other scenarios
import re
s = re.sub(r'\{\s+"t": ([^{}]*?)\s+\}', lambda m: '{ "t": ' + re.sub(r'\s+', ' ', m.group(1)) + ' }', s)
s = re.sub(r'\[\s+([-\d.e, \s]+?)\s+\]', lambda m: '[' + re.sub(r'\s+', ' ', m.group(1)) + ']', s)
open(args.out, 'w').write(s + "\n")
