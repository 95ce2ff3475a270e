#pragma once
// The scene's visible state copied into a render::RenderSnapshot (issue 8 item 4; DESIGN.md §5):
// what the trainer's simulation thread writes into the triple buffer's write slot after a frame,
// for the render thread to draw (engine/render/snapshot.hpp).
//
// Per body, live elements only, vertices compacted and indices remapped:
//   globe → Sclera, iris → Iris, cornea → Cornea, lens_surface → LensSurface,
//   capsule → Capsule with its open edges (edges of live triangles without a neighbour: the rim
//             and every cut), one BodyView each;
//   lens (tetrahedra, seed 000 §5.3) → two views: "lens", the faces of live tets on the lens's
//             original outer surface (LensSurface), and "lens.interior", the faces newly exposed
//             by sculpting (a live tet whose neighbour across the face was removed; LensInterior);
//   lens (simplex cells, seed 002 §5.2) → the boundary surface of systems/simplex; triangles whose
//             face nodes all were external at the first fill → "lens", the rest → "lens.interior".
//             Each vertex carries its fragment (BodyView::piece) so the pieces show apart.
//   Both lens models: reflex_attenuation_per_mm from the nucleus hardness (a cataract dims the red
//             reflex; the renderer brightens it where sculpting thinned the lens, issue 19 item 4).
// topology_version changes whenever a view's triangles or edges change (a 64-bit hash of them
// compared with the last fill's); versions come from one process-wide counter, so a rebuilt scene
// never repeats a version the renderer has cached. Tools: pose, kind, hand, grip, pedal;
// in_contact = forceps holding the capsule. Guidance from the drill file (scene.drill.guidance),
// ports and the globe's rotation from procedures/scene/tool_ports' record.
//
// Reads: bodies (Particles, Triangles, LensSculpting, LensFragments), tools (Tool, ToolState,
// ToolGrasp), the ports' record. Writes: the snapshot, and its own cache (a component on the
// scene's first body). Allocates only when a vector must grow (counts above their earlier peak)
// and on the first fill of a scene. Call on the simulation thread between frames.
#include "engine/render/snapshot.hpp"

namespace phaco {

struct Scene;

void fill_snapshot(Scene& scene, render::RenderSnapshot& snapshot);

}  // namespace phaco
