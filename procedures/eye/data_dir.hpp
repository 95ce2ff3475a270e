#pragma once
// Where the programs find their data (eye/, drills/, scenarios/), wherever they are installed:
//   1. $PHACO_DATA_DIR, when set;
//   2. ../share/openphaco beside the running executable (/proc/self/exe), when it holds the eye:
//      an installed or unpacked package (/usr/bin/phaco -> /usr/share/openphaco);
//   3. the source tree's data/, only for an executable inside the build tree it was built in
//      (developers, tests, the perf harness). An installed or copied binary never looks there.
#include <filesystem>
#include <string>

namespace phaco::eye {

struct DataDir {
  std::filesystem::path dir;
  std::string origin;  // "PHACO_DATA_DIR", "installed", "build tree"
};

// Throws InputError naming the folders it looked in when none holds the data.
DataDir locate_data_dir();

// locate_data_dir().dir.
std::filesystem::path data_dir();

}  // namespace phaco::eye
