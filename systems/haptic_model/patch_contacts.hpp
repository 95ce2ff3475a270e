#pragma once
// Internal to systems/haptic_model: the tip sphere against the published patch (haptic_model.hpp,
// steps 2–3): the triangles' normals, the contacts on each triangle's remembered side, and the
// proxy solved against the contact planes.
#include <array>
#include <cstdint>

#include "systems/haptic_model/haptic_model.hpp"
#include "systems/haptic_model/proxy_planes.hpp"

namespace phaco::haptic_model::detail {

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection §5.1.5), as
// barycentric weights; `inside` when it lies in the face's interior (not on an edge or corner).
void closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                         std::array<double, 3>& w, bool& inside);

// Each published triangle's unit normal and bounding radius, and whether it is usable.
void compute_normals(const HapticSlot& s, HapticScratch& sc);

// Contacts of the tip sphere at q with the patch, on each triangle's remembered side.
void gather_contacts(const HapticSlot& s, const HapticScratch& sc, const Vec3& q, double r,
                     const HapticSettings& st, std::array<HapticContact, kHapticMaxContacts>& list,
                     uint32_t& count);

// argmin ½k_c|P − D|² + Σ E_j(max(0, r − n_j·(P − p_j))), E_j the plane's energy (½k·pen², linear
// past its cap: proxy_planes.hpp): a strongly convex, piecewise quadratic energy. Newton on the
// piece the current P lies in (its 3×3 system solved exactly), with backtracking on the energy:
// plain piece-hopping can cycle between the pieces of a stiff valley (the proxy jumped tangentially
// there), the line search cannot. Warm-started from the last proxy; ≤ 12 rounds (2–3 typical).
Vec3 solve_proxy(const Vec3& d, const Vec3& start, double kc, double r, const Planes& planes,
                 uint32_t count);

}  // namespace phaco::haptic_model::detail
