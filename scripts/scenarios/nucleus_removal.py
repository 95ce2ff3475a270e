#!/usr/bin/env python3
"""Writes a scripted nucleus removal (issue 19): crack the grooved nucleus into quadrants with the
phaco probe (right hand) and the chopper (left hand), then occlude, hold and emulsify each quadrant.

usage: nucleus_removal.py OUT.json [--dip] [--wasteful] [--name N] [--description D]

The drill starts with the nucleus grooved by a cross (data/drills/nucleus_removal.json,
guidance.trench_cross: one trench along x, one along y, 1.35 mm wide, 80 % deep). The expert:
  1. both tips into the x trench at x = -1.2, on its walls, pushed apart across it: the nucleus
     cracks into two halves along y = 0;
  2. the same in the y trench of the -y half (at y = -1.2, then -0.8), then of the +y half
     (y = +1.2, then +0.8, higher, then +1.0 deep in the trench), pushed apart at ten places
     across the trench at each, since the halves move once apart (crack()): four quadrants;
  3. for each quadrant: the probe into its inner corner with aspiration (pedal 2) until the port
     occludes and the vacuum holds the quadrant, then ultrasound (pedal 3) while the vacuum feeds it
     into the tip; lift.
--dip      (novice) after the second quadrant the probe dips through the posterior capsule at the
           centre: a rupture.
--wasteful (novice) ultrasound (pedal 3) instead of aspiration while occluding, three seconds more
           of it on each quadrant (chasing it instead of letting the vacuum feed it in) and 3.5 s
           in the empty bag after it: about 1.6x the expert's CDE, so that the defect outlasts a
           cohort's +-15 % tempo (perf/cohorts). (Ultrasound on the way into a quadrant, tried,
           pushed the quadrants away from the unoccluded tip: a removal defect too.)
Each tool pivots in its corneal port (scripts/scenarios/ports.py): the probe in the main incision
(3 o'clock), the chopper in the side port (11 o'clock).
"""
import argparse, json, math, re
import ports
ap = argparse.ArgumentParser()
ap.add_argument("out")
ap.add_argument("--dip", action="store_true")
ap.add_argument("--wasteful", action="store_true")
ap.add_argument("--quadrant-s", type=float, default=11.0)
ap.add_argument("--cleanup-s", type=float, default=6.0)
ap.add_argument("--level", type=int, default=1)
ap.add_argument("--name", default="nucleus removal expert")
ap.add_argument("--description", default="Crack the grooved nucleus into quadrants with the probe and the chopper pushing apart in the trenches, then occlude, hold and emulsify each quadrant.")
args = ap.parse_args()

P = ports.default_ports("nucleus_removal")
main, main_axis = P["main"]
side, side_axis = P["side"]
rest_p = [main[i] + 0.25 * main_axis[i] for i in range(3)]
# The chopper rests deeper: its shaft's axis runs 1 mm beside its tip (the bent point, ports.py
# BEND_MM), and with the tip nearer the side port's centre than that the axis could pass the
# centre only across the tunnel; 0.25 mm in, it pressed the port 150 mN.
rest_c = [side[i] + (ports.BEND_MM["chopper"] + 1.25) * side_axis[i] for i in range(3)]

def inward(centre, r, z):
    """A point on the port's azimuth at radius r and height z: in the pupil, above the iris."""
    rho = math.hypot(centre[0], centre[1])
    return [centre[0] * r / rho, centre[1] * r / rho, z]

probe, chop = [], []
t = 0.0
def both(dt, p, pedal, c):
    global t
    t += dt
    probe.append({"t": round(t, 3), "pos": [round(v, 4) for v in p], "quat": [1, 0, 0, 0], "pedal": pedal})
    chop.append({"t": round(t, 3), "pos": [round(v, 4) for v in c], "quat": [1, 0, 0, 0]})
probe.append({"t": 0.0, "pos": [round(v, 4) for v in rest_p], "quat": [1, 0, 0, 0], "pedal": 0})
chop.append({"t": 0.0, "pos": [round(v, 4) for v in rest_c], "quat": [1, 0, 0, 0]})

Z_CRACK = -0.3   # 0.96 mm above the trench floor at the centre (-1.26)
Z_ABOVE = 2.0    # over the lens, under the iris plane's height of the port
park_p = inward(main, 3.0, Z_ABOVE)
park_c = inward(side, 3.0, Z_ABOVE)
both(1.0, park_p, 1, park_c)

def crack(mid, d, offsets, sep=(1.0, 1.8), z=None):
    """The probe and the chopper down in a trench about `mid` (x, y), on either side along `d`
    (the unit push, chopper -> probe), then, at each of `offsets` (mm along `d` from `mid`, in
    turn), pushed apart from sep[0] to sep[1] and brought back together as they move on; lifted.
    Why several places: a half that moved after the first crack carries its trench along (0.15-0.5
    mm at 1.2 mm from the centre, the carried trench of a procedure more than the drill's groove,
    and the pieces settle differently run to run), and blind tips cannot see where it went. The
    push cracks where it engages (lens_tools/crack: both tips on the fragment, no cell at their
    midpoint, then 0.2 mm more spread); bringing the tips together re-arms it for the next place.
    The spread runs past the trench's width (1.35 mm in the drill, 1.5 in the procedure's carried
    trench) into its walls, as a surgeon's does: to 1.8 mm (it was 1.6, 1.4 for the first crack),
    more slowly (0.45 s); to 2.0 mm the drill removed less after the cracks (0.40 of the lens
    instead of 0.73, one run each; docs/nucleus_removal.md)."""
    def at(c, h): return [mid[0] + (c + h) * d[0], mid[1] + (c + h) * d[1]]
    zc = Z_CRACK if z is None else z
    o = offsets[0]
    both(0.8, at(o, 0.5 * sep[0]) + [Z_ABOVE], 1, at(o, -0.5 * sep[0]) + [Z_ABOVE])
    both(0.6, at(o, 0.5 * sep[0]) + [zc], 1, at(o, -0.5 * sep[0]) + [zc])
    for k, o in enumerate(offsets):
        if k:
            both(0.2, at(o, 0.5 * sep[0]) + [zc], 1, at(o, -0.5 * sep[0]) + [zc])
        both(0.45, at(o, 0.5 * sep[1]) + [zc], 1, at(o, -0.5 * sep[1]) + [zc])
    both(0.6, at(o, 0.5 * sep[1]) + [Z_ABOVE], 1, at(o, -0.5 * sep[1]) + [Z_ABOVE])

Y_ROWS = (1.2, 0.8)
ACROSS = [-0.8, -0.6, -0.4, -0.2, 0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
crack([-1.2, 0.0], [0.0, -1.0], [0.0], sep=(0.8, 1.8))  # along the x trench: two halves
# Each y crack is tried 1.2 mm from the centre, then 0.8 mm: once the halves part they sink and
# tip toward the x crack, by how much depends on the lens's resolution (their centroids sit at
# |y| = 0.57 mm at level 3, 1.2 mm at level 1), and at the tips' height the slice out at 1.2 mm
# passes under the y trench's floor at level 3 while the one at 0.8 mm is closed at level 0 (+y
# half). A blind hand tries both; once a half has cracked, the second row straddles the crack.
for y in Y_ROWS:
    crack([0.0, -y], [1.0, 0.0], ACROSS)   # the -y half along the y trench
# The +y half at 1.2 and 0.8 mm 0.4 mm above the -y rows, then deep in its trench at 1.0 mm as
# a last try. Where it lies after the first two cracks varies from run to run (it sinks and tips
# toward the x crack while the -y half is cracked): under a cohort's tremor, tempo and offsets the
# two high rows alone cracked it in 1 of 3 hands tried (docs/nucleus_removal.md); the deep row
# at 1.0 mm cracked one of those that missed, and with it every hand tried cracked it.
Y_PLUS_ROWS = ((1.2, 0.1), (0.8, 0.1), (1.0, -0.5))
for y, z in Y_PLUS_ROWS:
    crack([0.0, y], [1.0, 0.0], ACROSS, z=z)  # the +y half

chopper_park = [-1.0, 0.0, Z_ABOVE]
occlude_pedal = 3 if args.wasteful else 2
for k, (sx, sy) in enumerate(((1, 1), (1, -1), (-1, 1), (-1, -1))):
    # Into the quadrant (pedal 1), then aspirating while sweeping toward the centre: the port
    # occludes on the quadrant wherever it now lies, the vacuum holds it and it follows the tip
    # to the middle of the bag, away from the capsule; there ultrasound emulsifies it as the
    # vacuum feeds it in.
    both(0.6, [sx * 1.6, sy * 1.6, 1.6], 1, chopper_park)
    both(0.5, [sx * 1.6, sy * 1.6, -0.2], 1, chopper_park)
    both(0.05, [sx * 1.6, sy * 1.6, -0.2], occlude_pedal, chopper_park)
    both(1.2, [sx * 0.5, sy * 0.5, 0.0], occlude_pedal, chopper_park)
    both(0.05, [sx * 0.5, sy * 0.5, 0.0], 3, chopper_park)
    both(args.quadrant_s + (3.0 if args.wasteful else 0.0), [sx * 0.5, sy * 0.5, 0.0], 3,
         chopper_park)
    if args.wasteful:
        both(3.5, [sx * 0.5, sy * 0.5, 0.0], 3, chopper_park)   # ultrasound in the empty bag
    both(0.05, [sx * 0.5, sy * 0.5, 0.0], 1, chopper_park)
    both(0.4, [sx * 1.0, sy * 1.0, 1.6], 1, chopper_park)
    if args.dip and k == 1:
        both(0.6, [0.0, 0.0, 0.0], 1, chopper_park)
        # through the posterior pole (z = -2.7) by 0.8 mm: more than 5 sigma of a cohort's
        # offsets (perf/cohorts, 0.15 mm per axis), which at 0.2 mm past it missed 2 ruptures of 4
        both(0.6, [0.0, 0.0, -3.5], 1, chopper_park)
        both(0.6, [0.0, 0.0, 1.6], 1, chopper_park)
# What is left rests at the bottom of the bag's bowl: occlude on it there and emulsify it.
both(0.6, [0.3, 0.0, 1.0], 1, chopper_park)
both(0.05, [0.3, 0.0, 1.0], occlude_pedal, chopper_park)
both(1.0, [0.0, 0.0, -1.0], occlude_pedal, chopper_park)
both(0.05, [0.0, 0.0, -1.0], 3, chopper_park)
both(args.cleanup_s, [0.0, 0.0, -0.6], 3, chopper_park)
both(0.05, [0.0, 0.0, -0.6], 1, chopper_park)
both(0.8, park_p, 1, park_c)
both(0.8, rest_p, 0, rest_c)

inside = ports.inside_eye()
probe = ports.pivot_track(probe, main, main_axis, inside)
chop = ports.pivot_track(chop, side, side_axis, inside, bend=ports.BEND_MM["chopper"])
sc = {
  "name": args.name,
  "description": args.description,
  "drill": "nucleus_removal",
  "eye": {"level": args.level},
  "dt_s": 1/120,
  "seed": 19,
  "duration_s": round(t, 3),
  "hands": {"left": {"tool": "chopper", "track": chop},
            "right": {"tool": "phaco_probe", "track": probe}}
}
s = json.dumps(sc, indent=2)
s = re.sub(r'\{\s+"t": ([^{}]*?)\s+\}', lambda m: '{ "t": ' + re.sub(r'\s+', ' ', m.group(1)) + ' }', s)
s = re.sub(r'\[\s+([-\d.e, \s]+?)\s+\]', lambda m: '[' + re.sub(r'\s+', ' ', m.group(1)) + ']', s)
open(args.out, 'w').write(s + "\n")
