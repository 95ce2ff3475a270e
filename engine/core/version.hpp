#pragma once
// The build's identity, so a score or a figure can be traced to the build that made it: the
// version of CMake's project() and the source revision, captured at build time by
// cmake/revision.cmake into a generated source ("unknown" for a tree without git, "-dirty" when
// it had uncommitted changes).
namespace phaco {

const char* version();   // "0.1.0"
const char* revision();  // "d46c276a1b2c", "d46c276a1b2c-dirty" or "unknown"

}  // namespace phaco
