#include "torsion/mesh/mesh_io.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "error_matchers.h"
#include "test_meshes.h"

namespace torsion {
namespace {

namespace fs = std::filesystem;
using test::failsWith;

class MeshIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("torsion_mesh_io_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  fs::path dir_;
};

TEST_F(MeshIo, MissingFileNamesPathAndReason) {
  EXPECT_TRUE(failsWith(readMesh(dir_ / "nope.msh"), {"nope.msh: cannot open", "No such file"}));
}

TEST_F(MeshIo, EmptyFile) {
  write("e.vtk", "  \n\n");
  EXPECT_TRUE(failsWith(readMesh(dir_ / "e.vtk"), {"e.vtk: file is empty"}));
}

TEST_F(MeshIo, DirectoryIsNotAMesh) {
  fs::create_directories(dir_ / "d.msh");
  EXPECT_TRUE(failsWith(readMesh(dir_ / "d.msh"), {"d.msh: cannot open: is a directory"}));
}

TEST_F(MeshIo, UnknownExtensionListsKnownOnes) {
  write("m.obj", "v 0 0 0\n");
  EXPECT_TRUE(failsWith(readMesh(dir_ / "m.obj"), {"unknown mesh format '.obj'", ".msh", ".vtk"}));
}

TEST_F(MeshIo, TetGenPairByAnyOfItsNames) {
  write("cube.node", test::kCubeNode);
  write("cube.ele", test::kCubeEle);
  for (const char* name : {"cube", "cube.node", "cube.ele"}) {
    Result<LoadedMesh> loaded = readMesh(dir_ / name);
    ASSERT_TRUE(loaded.ok()) << name << ": " << loaded.error().message;
    EXPECT_EQ(loaded.value().mesh.tetCount(), 5);
  }
}

TEST_F(MeshIo, TetGenMissingEleNamesIt) {
  write("half.node", test::kCubeNode);
  EXPECT_TRUE(failsWith(readMesh(dir_ / "half.node"), {"half.ele: cannot open"}));
}

TEST_F(MeshIo, EveryFormatRoundTrips) {
  write("cube.node", test::kCubeNode);
  write("cube.ele", test::kCubeEle);
  const TetMesh original = readMesh(dir_ / "cube.node").value().mesh;
  for (const char* name : {"out.node", "out.msh", "out.vtk"}) {
    Status written = writeMesh(dir_ / name, original);
    ASSERT_TRUE(written.ok()) << written.error().message;
    Result<LoadedMesh> again = readMesh(dir_ / name);
    ASSERT_TRUE(again.ok()) << name << ": " << again.error().message;
    EXPECT_EQ(again.value().mesh.restPositions(), original.restPositions()) << name;
    EXPECT_EQ(again.value().mesh.tets(), original.tets()) << name;
    EXPECT_TRUE(again.value().warnings.empty()) << name;
  }
}

TEST_F(MeshIo, WriteToMissingDirectoryFails) {
  write("cube.node", test::kCubeNode);
  write("cube.ele", test::kCubeEle);
  const TetMesh mesh = readMesh(dir_ / "cube").value().mesh;
  EXPECT_TRUE(
      failsWith(writeMesh(dir_ / "no" / "such" / "dir.vtk", mesh), {"dir.vtk: cannot write"}));
}

}  // namespace
}  // namespace torsion
