#pragma once
// Math aliases over Eigen. Geometry generation and cold data use double; hot per-element state
// (particles) is float SoA in components/.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace phaco {

using Vec3 = Eigen::Vector3d;
using Vec3f = Eigen::Vector3f;
using Quat = Eigen::Quaterniond;  // (w, x, y, z); unit length when it is a rotation

}  // namespace phaco
