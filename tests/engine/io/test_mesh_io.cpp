// OBJ and TetGen .node/.ele: exact round trips, the accepted dialects, and errors naming FILE:LINE.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "engine/core/error.hpp"
#include "engine/io/mesh_obj.hpp"
#include "engine/io/tetgen_files.hpp"

namespace phaco {
namespace {
namespace fs = std::filesystem;

class MeshIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("phaco_mesh_io_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  // The InputError message of fn, or "" if it did not throw one.
  template <typename Fn>
  static std::string error_of(Fn fn) {
    try {
      fn();
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

// Values that a %.6g writer would lose: irrational, tiny, huge, negative zero, subnormal.
SurfaceMesh awkward_mesh() {
  SurfaceMesh m;
  m.vertices = {Vec3(std::sqrt(2.0), -1.0 / 3.0, 1e-300), Vec3(0.1 + 0.2, -0.0, 6.02214076e23),
                Vec3(std::numeric_limits<double>::denorm_min(), 4.7, -2.7),
                Vec3(std::nextafter(1.0, 2.0), std::numeric_limits<double>::max(), 5.33)};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TEST_F(MeshIo, ObjRoundTripIsExact) {
  const SurfaceMesh m = awkward_mesh();
  write_obj(dir_ / "a.obj", m);
  const SurfaceMesh r = read_obj(dir_ / "a.obj");
  ASSERT_EQ(r.vertices.size(), m.vertices.size());
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(std::signbit(r.vertices[i][k]), std::signbit(m.vertices[i][k]));
      EXPECT_EQ(r.vertices[i][k], m.vertices[i][k]) << i << "," << k;
    }
  }
  EXPECT_EQ(r.triangles, m.triangles);
}

TEST_F(MeshIo, ObjReadsCommonDialects) {
  const auto p = write("d.obj",
                       "# exported elsewhere\r\n"
                       "mtllib x.mtl\n"
                       "o thing\n"
                       "v 0 0 0\nv 1 0 0 1.0\nv 1 1 0\nv 0 1 0\n"
                       "vn 0 0 1\nvt 0 0\n"
                       "s off\nusemtl m\n"
                       "f 1/1/1 2/1/1 3/1/1\n"  // v/t/n
                       "f -4//1 -2//1 -1//1\n"  // negative v//n
                       "\n"
                       "f 1 2 3 4   # a quad, fan-triangulated\n");
  const SurfaceMesh m = read_obj(p);
  ASSERT_EQ(m.vertices.size(), 4u);
  using Tri = std::array<uint32_t, 3>;
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (Tri{0, 2, 3}));
  EXPECT_EQ(m.triangles[2], (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangles[3], (Tri{0, 2, 3}));
}

struct BadText {
  const char* name;
  const char* text;
  int line;            // expected line in the message
  const char* detail;  // expected words in the message
};

TEST_F(MeshIo, ObjRejectsMalformedFilesNamingFileAndLine) {
  const BadText cases[] = {
      {"bad_number", "v 0 0 0\nv 1 x 0\n", 2, "bad number"},
      {"nan", "v 0 0 0\nv 1 nan 0\n", 2, "non-finite"},
      {"inf", "v inf 0 0\n", 1, "non-finite"},
      {"short_vertex", "v 1 2\n", 1, "three coordinates"},
      {"zero_index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 4, "out of range"},
      {"index_high", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n", 5, "out of range"},
      {"negative_far", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", 4, "out of range"},
      {"two_corners", "v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "three corners"},
      {"bad_index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3.5\n", 4, "bad integer"},
      {"forward_ref", "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", 1, "out of range"},
  };
  for (const auto& c : cases) {
    const auto p = write(std::string(c.name) + ".obj", c.text);
    const std::string msg = error_of([&] { read_obj(p); });
    EXPECT_NE(msg.find(p.string() + ":" + std::to_string(c.line) + ":"), std::string::npos)
        << c.name << ": " << msg;
    EXPECT_NE(msg.find(c.detail), std::string::npos) << c.name << ": " << msg;
  }
  const std::string missing = error_of([&] { read_obj(dir_ / "absent.obj"); });
  EXPECT_NE(missing.find("absent.obj"), std::string::npos) << missing;
}

TEST_F(MeshIo, TetgenRoundTripIsExact) {
  TetMesh m;
  const SurfaceMesh s = awkward_mesh();
  m.vertices = s.vertices;
  m.vertices.emplace_back(1.0 / 7.0, -1e-17, 2.5);
  m.tets = {{0, 1, 2, 3}, {1, 2, 3, 4}};
  m.region = {1, 0};
  write_tetgen(dir_ / "lens", m);
  EXPECT_TRUE(fs::exists(dir_ / "lens.node"));
  EXPECT_TRUE(fs::exists(dir_ / "lens.ele"));
  const TetMesh r = read_tetgen(dir_ / "lens");
  EXPECT_EQ(r.vertices, m.vertices);
  EXPECT_EQ(r.tets, m.tets);
  EXPECT_EQ(r.region, m.region);
}

TEST_F(MeshIo, TetgenAcceptsZeroBasedMarkersAndAttributes) {
  write("z.node",
        "# written by tetgen -z\n"
        "4 3 1 1\n"
        "0 0 0 0 7.5 1\n1 1 0 0 7.5 0\n2 0 1 0 7.5 1\n3 0 0 1 7.5 0\n");
  write("z.ele", "1 4 0\n0 0 1 2 3\n");
  const TetMesh m = read_tetgen(dir_ / "z");
  ASSERT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.vertices[3], Vec3(0, 0, 1));
  ASSERT_EQ(m.tets.size(), 1u);
  EXPECT_EQ(m.tets[0], (std::array<uint32_t, 4>{0, 1, 2, 3}));
  EXPECT_EQ(m.region[0], 0);
}

struct BadTetgen {
  const char* name;
  const char* node;
  const char* ele;
  const char* file;  // ".node" or ".ele"
  int line;
  const char* detail;
};

TEST_F(MeshIo, TetgenRejectsMalformedFilesNamingFileAndLine) {
  const char* good_node = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
  const char* good_ele = "1 4 1\n1 1 2 3 4 1\n";
  const BadTetgen cases[] = {
      {"nan", "4 3 0 0\n1 0 0 0\n2 nan 0 0\n3 0 1 0\n4 0 0 1\n", good_ele, ".node", 3,
       "non-finite"},
      {"short", "4 3 0 0\n1 0 0 0\n2 1 0 0\n", good_ele, ".node", 3, "file ends"},
      {"sequence", "4 3 0 0\n1 0 0 0\n3 1 0 0\n3 0 1 0\n4 0 0 1\n", good_ele, ".node", 3,
       "out of sequence"},
      {"base", "4 3 0 0\n5 0 0 0\n6 1 0 0\n7 0 1 0\n8 0 0 1\n", good_ele, ".node", 2,
       "start at 0 or 1"},
      {"dim", "4 2 0 0\n", good_ele, ".node", 1, "dimension"},
      {"columns", "4 3 0 0\n1 0 0 0\n2 1 0\n3 0 1 0\n4 0 0 1\n", good_ele, ".node", 3, "columns"},
      {"node_range", good_node, "1 4 1\n1 1 2 3 5 1\n", ".ele", 2, "out of range"},
      {"zero_in_one_based", good_node, "1 4 0\n1 0 1 2 3\n", ".ele", 2, "out of range"},
      {"region", good_node, "1 4 1\n1 1 2 3 4 2.5\n", ".ele", 2, "region"},
      {"extra", good_node, "1 4 1\n1 1 2 3 4 1\n2 1 2 3 4 1\n", ".ele", 3, "more tets"},
      {"corners", good_node, "1 5 0\n1 1 2 3 4 4\n", ".ele", 1, "4 or 10"},
      {"bad_int", good_node, "1 4 0\n1 1 2 three 4\n", ".ele", 2, "bad integer"},
  };
  for (const auto& c : cases) {
    write(std::string(c.name) + ".node", c.node);
    write(std::string(c.name) + ".ele", c.ele);
    const std::string msg = error_of([&] { read_tetgen(dir_ / c.name); });
    const std::string where =
        (dir_ / c.name).string() + c.file + ":" + std::to_string(c.line) + ":";
    EXPECT_NE(msg.find(where), std::string::npos) << c.name << ": " << msg;
    EXPECT_NE(msg.find(c.detail), std::string::npos) << c.name << ": " << msg;
  }
  const std::string missing = error_of([&] { read_tetgen(dir_ / "absent"); });
  EXPECT_NE(missing.find("absent.node"), std::string::npos) << missing;
}

}  // namespace
}  // namespace phaco
