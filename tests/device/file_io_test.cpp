#include "torsion/device/file_io.h"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace torsion::device {
namespace {

namespace fs = std::filesystem;

// A fresh directory per test under the system's temporary directory; never a real /dev file.
class FileIo : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "torsion_file_io_XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr) << std::strerror(errno);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void put(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
  }
  std::string contents(const std::string& name) const {
    std::ifstream in(dir_ / name);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  // Nothing but these names in the directory: no temporary (".tmp-", ".old-") was left.
  void expectOnly(std::initializer_list<std::string> names) const {
    std::vector<std::string> found;
    for (const fs::directory_entry& e : fs::directory_iterator(dir_))
      found.push_back(e.path().filename().string());
    std::sort(found.begin(), found.end());
    std::vector<std::string> expected(names);
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(found, expected);
  }
  fs::file_type typeOf(const std::string& name) const {
    return fs::symlink_status(dir_ / name).type();
  }

  fs::path dir_;
};

TEST_F(FileIo, ReplacesARegularFileAndCreatesAMissingOne) {
  put("a.txt", "old\n");
  EXPECT_EQ(writeFileAtomically(path("a.txt"), "new\n"), "");
  EXPECT_EQ(writeFileAtomically(path("b.txt"), "fresh\n"), "");
  EXPECT_EQ(contents("a.txt"), "new\n");
  EXPECT_EQ(contents("b.txt"), "fresh\n");
  expectOnly({"a.txt", "b.txt"});
}

TEST_F(FileIo, AFifoIsRefusedAndStaysAFifo) {
  ASSERT_EQ(::mkfifo(path("pipe").c_str(), 0600), 0) << std::strerror(errno);
  EXPECT_EQ(writeFileAtomically(path("pipe"), "text\n"),
            path("pipe") + ": cannot write: is a FIFO, not a regular file");
  EXPECT_EQ(typeOf("pipe"), fs::file_type::fifo);
  expectOnly({"pipe"});
}

TEST_F(FileIo, ASymbolicLinkIsRefusedAndItsTargetKept) {
  put("target.txt", "kept\n");
  fs::create_symlink(dir_ / "target.txt", dir_ / "link.txt");
  EXPECT_EQ(writeFileAtomically(path("link.txt"), "text\n"),
            path("link.txt") + ": cannot write: is a symbolic link, not a regular file");
  EXPECT_EQ(typeOf("link.txt"), fs::file_type::symlink);
  EXPECT_EQ(contents("target.txt"), "kept\n");
  // A dangling link is a link too: nothing is created where it points.
  fs::create_symlink(dir_ / "nowhere.txt", dir_ / "dangling.txt");
  EXPECT_EQ(writeFileAtomically(path("dangling.txt"), "text\n"),
            path("dangling.txt") + ": cannot write: is a symbolic link, not a regular file");
  expectOnly({"target.txt", "link.txt", "dangling.txt"});
}

TEST_F(FileIo, ADirectoryAndASocketAreRefusedByKind) {
  fs::create_directories(dir_ / "d.vtk" / "inside");
  EXPECT_EQ(writeFileAtomically(path("d.vtk"), "text\n"),
            path("d.vtk") + ": cannot write: is a directory, not a regular file");

  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  const std::string socket_path = path("sock");
  ASSERT_LT(socket_path.size(), sizeof address.sun_path);
  std::strcpy(address.sun_path, socket_path.c_str());
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address), 0)
      << std::strerror(errno);
  EXPECT_EQ(writeFileAtomically(socket_path, "text\n"),
            socket_path + ": cannot write: is a socket, not a regular file");
  ::close(fd);
  EXPECT_EQ(typeOf("sock"), fs::file_type::socket);
  expectOnly({"d.vtk", "sock"});
}

TEST_F(FileIo, FilesTogetherRefuseAFifoAndReplaceNone) {
  put("m.node", "old node\n");
  ASSERT_EQ(::mkfifo(path("m.ele").c_str(), 0600), 0) << std::strerror(errno);
  EXPECT_EQ(writeFilesTogether({{path("m.node"), "new node\n"}, {path("m.ele"), "new ele\n"}}),
            path("m.ele") + ": cannot write: is a FIFO, not a regular file");
  EXPECT_EQ(contents("m.node"), "old node\n");
  EXPECT_EQ(typeOf("m.ele"), fs::file_type::fifo);
  expectOnly({"m.node", "m.ele"});
}

TEST_F(FileIo, FilesTogetherRefuseASymbolicLink) {
  put("target", "kept\n");
  fs::create_symlink(dir_ / "target", dir_ / "m.node");
  EXPECT_EQ(writeFilesTogether({{path("m.node"), "node\n"}, {path("m.ele"), "ele\n"}}),
            path("m.node") + ": cannot write: is a symbolic link, not a regular file");
  EXPECT_EQ(typeOf("m.node"), fs::file_type::symlink);
  EXPECT_EQ(contents("target"), "kept\n");
  expectOnly({"target", "m.node"});
}

TEST_F(FileIo, ARowFileOpensOnlyOverARegularFile) {
  ASSERT_EQ(::mkfifo(path("rows.csv").c_str(), 0600), 0) << std::strerror(errno);
  put("target.csv", "kept\n");
  fs::create_symlink(dir_ / "target.csv", dir_ / "link.csv");
  RowFile rows;
  EXPECT_EQ(rows.open(path("rows.csv")),
            path("rows.csv") + ": cannot write: is a FIFO, not a regular file");
  EXPECT_EQ(rows.open(path("link.csv")),
            path("link.csv") + ": cannot write: is a symbolic link, not a regular file");
  EXPECT_FALSE(rows.isOpen());
  EXPECT_EQ(contents("target.csv"), "kept\n");
  put("old.csv", "old rows\n");
  ASSERT_EQ(rows.open(path("old.csv")), "");
  EXPECT_EQ(rows.write("a,b\n"), "");
  EXPECT_EQ(rows.close(), "");
  EXPECT_EQ(contents("old.csv"), "a,b\n");
}

}  // namespace
}  // namespace torsion::device
