#pragma once
// The unit change the scene's builders share: the eye files give densities in kg/m³, the meshes
// are in mm.

namespace phaco {

inline constexpr double kKgPerMm3PerKgPerM3 = 1e-9;  // density kg/m³ → kg/mm³

}  // namespace phaco
