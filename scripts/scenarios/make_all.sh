#!/usr/bin/env bash
# Regenerates the expert and novice drill scenarios (issue 7) in data/scenarios from the demos.
# Every tool but the keratome pivots in its corneal port (ports.py; docs/tool_eye_interaction.md).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
out="$here/../../data/scenarios"
rhexis() { python3 "$here/capsulorhexis.py" "$@"; }
sculpt() { python3 "$here/sculpting.py" "$@"; }

rhexis "$out/capsulorhexis_expert.json" --scale 1.04 --name "capsulorhexis expert" \
  --description "The demo's technique at a 5.3 mm circle: puncture near the centre, a short radial flap, four quarters with a regrasp after each; meets every rhexis target."
rhexis "$out/capsulorhexis_novice_off_centre.json" --scale 1.04 --shift 0.7,0 --name "capsulorhexis novice: off centre" \
  --description "The expert's tracks moved 0.7 mm toward 3 o'clock: the opening is the right size but decentred."
rhexis "$out/capsulorhexis_novice_runout.json" --scale 1.04 --outward 5.3,6.5,0.45 --name "capsulorhexis novice: radial run-out" \
  --description "The expert's tracks, but in the second quarter the forceps pull outward (radius growing by 45 %): the tear runs out radially."
rhexis "$out/capsulorhexis_novice_small.json" --scale 0.9 --name "capsulorhexis novice: too small" \
  --description "The demo's technique at a 4.4 mm circle: complete and round but too small."
sculpt "$out/phaco_sculpting_expert.json" --name "phaco sculpting expert" \
  --description "Divide and conquer: two trenches of four passes, two lanes each, the first pass shaving the surface so that each trench is an open groove; a quarter turn between them."
sculpt "$out/phaco_sculpting_novice_shallow.json" --passes 0.8,1.5 --name "phaco sculpting novice: shallow trenches" \
  --description "Only the first two passes of each trench: the trenches are about 40 % of the nucleus deep."
sculpt "$out/phaco_sculpting_novice_narrow.json" --lanes 0 --name "phaco sculpting novice: narrow trenches" \
  --description "One lane per pass: the trenches are about one tip wide (0.8 mm), below 1.5 tip diameters."
incision() { python3 "$here/incision.py" "$@"; }
incision "$out/corneal_incision_expert.json" --name "corneal incision expert" \
  --description "A straight keratome pass at 3 o'clock, 0.5 mm inside the limbus, 28 degrees below the corneal surface: a 1.7 mm tunnel into the anterior chamber; meets every incision target."
incision "$out/corneal_incision_novice_steep.json" --angle 60 --name "corneal incision novice: too steep" \
  --description "The expert's pass at 60 degrees below the corneal surface: the same site and width, but the tunnel is under 1 mm (a leaking wound)."
incision "$out/corneal_incision_novice_site.json" --limbus 1.6 --name "corneal incision novice: too far inside the limbus" \
  --description "The expert's pass started 1.6 mm inside the limbus: a good tunnel, but in the clear cornea away from the limbus."
nucleus() { python3 "$here/nucleus_removal.py" "$@"; }
nucleus "$out/nucleus_removal_expert.json" --name "nucleus removal expert" \
  --description "Three cracks with the probe and the chopper pushing apart in the grooved cross (two halves, then each half into quadrants); each quadrant occluded with aspiration while sweeping to the centre, held and emulsified there; what is left emulsified at the bottom of the bag."
nucleus "$out/nucleus_removal_novice_rupture.json" --dip --name "nucleus removal novice: posterior capsule rupture" \
  --description "The expert's hands, but after the second quadrant the probe dips through the posterior pole of the bag: a posterior capsule rupture, which fails the drill."
nucleus "$out/nucleus_removal_novice_wasteful.json" --wasteful --name "nucleus removal novice: wasteful ultrasound" \
  --description "The expert's hands, but with ultrasound (pedal 3) instead of aspiration while occluding, three more seconds of it on each quadrant and three and a half in the empty bag after it: about 1.6 times the expert's cumulative dissipated energy."
