// A scene's .bullet file is untrusted input: Bullet's reader runs in a child process of its own
// (isolated_call.h), and the bodies it describes are read back through the scene parser's checks
// (bullet_file_import.h). Corrupted files, lying headers, hostile names, constraints and shapes a
// scene cannot describe all end as errors naming the scene, the key and the file.
#include <BulletCollision/CollisionShapes/btCylinderShape.h>
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <iterator>
#include <memory>
#include <new>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "isolated_call.h"
#include "scene_parser.h"

namespace torsion::scene {
namespace {

const std::string kShipped = std::string(TORSION_ASSETS_DIR) + "/../bullet/boxes.bullet";

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A file in the test's temporary folder, removed when it goes out of scope.
struct TempFile {
  std::string path;
  explicit TempFile(std::string file_path) : path(std::move(file_path)) {}
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() { std::remove(path.c_str()); }
};

std::unique_ptr<TempFile> writeTemp(const std::string& name, const std::string& bytes) {
  auto file = std::make_unique<TempFile>(::testing::TempDir() + "bullet_import_" +
                                         std::to_string(getpid()) + "_" + name + ".bullet");
  std::ofstream(file->path, std::ios::binary) << bytes;
  return file;
}

// A scene with one FEM body (named `fem_name`) and the .bullet file at `path`.
Result<SceneSpec> parseWith(const std::string& path, const std::string& fem_name = "slab") {
  const std::string text = R"({"bodies": [{"name": ")" + fem_name + R"(", "mesh": ")" +
                           std::string(TORSION_ASSETS_DIR) +
                           R"(/slab_768.node", "material": {"youngs_modulus": 5e4,
                           "poisson_ratio": 0.3, "density": 300}}], "bullet_file": ")" +
                           path + R"("})";
  return parseScene(text, "b.json", "/base");
}

// A rigid-body world built by `fill` and written by Bullet's serializer: a .bullet file's bytes.
struct SerializedWorld {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &configuration};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  std::vector<std::unique_ptr<btTypedConstraint>> constraints;
  btDefaultSerializer serializer;

  ~SerializedWorld() {
    for (auto& c : constraints)
      world.removeConstraint(c.get());
    for (auto& b : bodies)
      world.removeRigidBody(b.get());
  }
  btRigidBody* add(std::unique_ptr<btCollisionShape> shape, double mass, const btVector3& at,
                   const char* name = nullptr) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(btScalar(mass), inertia);
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass), nullptr, shape.get(), inertia);
    info.m_startWorldTransform.setOrigin(at);
    bodies.push_back(std::make_unique<btRigidBody>(info));
    shapes.push_back(std::move(shape));
    world.addRigidBody(bodies.back().get());
    if (name != nullptr) serializer.registerNameForPointer(bodies.back().get(), name);
    return bodies.back().get();
  }
  std::string bytes() {
    world.serialize(&serializer);
    return {reinterpret_cast<const char*>(serializer.getBufferPointer()),
            static_cast<size_t>(serializer.getCurrentBufferSize())};
  }
};

std::unique_ptr<btCollisionShape> box(double half) {
  return std::make_unique<btBoxShape>(btVector3(btScalar(half), btScalar(half), btScalar(half)));
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(BulletFileImport, TheShippedFileGivesItsBodiesAsSceneRigidBodies) {
  Result<SceneSpec> spec = parseWith(kShipped);
  ASSERT_TRUE(spec.ok()) << spec.error().message;
  // assets/README.md: a static ground box (half extents 3 x 3 x 0.5 m, top at z = 0) and three
  // 0.2 m boxes dropped from 0.8, 1.1 and 1.4 m, unnamed in the file.
  const std::vector<RigidBodySpec>& bodies = spec.value().rigid_bodies;
  ASSERT_EQ(bodies.size(), 4u);
  EXPECT_EQ(bodies[0].name, "boxes_0");
  EXPECT_EQ(bodies[0].mass, 0.0);
  // Within float rounding: a box's collision margin is a float in the file
  // (btConvexInternalShapeData), and float Bullet reads the file's doubles into floats.
  const double rounding = 1e-6;
  EXPECT_NEAR((bodies[0].half_extents - Eigen::Vector3d(3, 3, 0.5)).norm(), 0, rounding);
  EXPECT_NEAR(bodies[0].pose.origin.z(), -0.5, rounding);
  const double heights[] = {0.8, 1.1, 1.4};
  for (size_t k = 1; k < 4; ++k) {
    EXPECT_EQ(bodies[k].shape, RigidBodySpec::Shape::kBox);
    EXPECT_GT(bodies[k].mass, 0.0) << k;
    EXPECT_NEAR((bodies[k].half_extents - Eigen::Vector3d::Constant(0.1)).norm(), 0, rounding);
    EXPECT_NEAR(bodies[k].pose.origin.z(), heights[k - 1], rounding) << k;
  }
}

// One byte of the header changes how Bullet reads every other byte: 'd' -> 'f' (float data),
// '-' -> '_' (4-byte pointers), 'v' -> 'V' (big-endian). Each segfaulted Bullet's reader in
// this process or loaded every body at the origin.
TEST(BulletFileImport, AHeaderThatLiesAboutItsDataIsRefused) {
  const std::string original = readBytes(kShipped);
  ASSERT_EQ(original.substr(0, 9), "BULLETd-v");
  const std::pair<size_t, char> lies[] = {{6, 'f'}, {7, '_'}, {8, 'V'}};
  for (const auto& [offset, byte] : lies) {
    std::string bytes = original;
    bytes[offset] = byte;
    const auto file = writeTemp(std::string("header_") + byte, bytes);
    const std::string& path = file->path;
    Result<SceneSpec> spec = parseWith(path);
    ASSERT_FALSE(spec.ok()) << "header byte " << offset << " = " << byte;
    std::cout << "[figures] header byte " << offset << " = '" << byte
              << "': " << spec.error().message << "\n";
    EXPECT_TRUE(contains(spec.error().message, "b.json: bullet_file: " + path + ": "))
        << spec.error().message;
  }
}

// 300 corruptions of the shipped file (random bytes overwritten, or the file cut short), seeded:
// each ends as an error naming the scene and the file, or as bodies that passed the scene's
// checks. Today's reader in this process crashed on some (heap overflows in bParse under ASan,
// segfaults in Release): this test would have died with it.
TEST(BulletFileImport, CorruptedFilesEndAsErrorsOrCheckedBodiesNeverAsACrash) {
  const std::string original = readBytes(kShipped);
  std::mt19937 random(20261129);
  int refused = 0, loaded = 0, crashed_reader = 0;
  for (int k = 0; k < 300; ++k) {
    std::string bytes = original;
    if (k % 5 == 0) {
      bytes.resize(std::uniform_int_distribution<size_t>(0, bytes.size() - 1)(random));
    } else {
      const int changes = std::uniform_int_distribution<int>(1, 8)(random);
      for (int c = 0; c < changes; ++c) {
        bytes[std::uniform_int_distribution<size_t>(0, bytes.size() - 1)(random)] =
            static_cast<char>(std::uniform_int_distribution<int>(0, 255)(random));
      }
    }
    const auto file = writeTemp("corrupt", bytes);
    const std::string& path = file->path;
    Result<SceneSpec> spec = parseWith(path);
    if (spec.ok()) {
      ++loaded;
      for (const RigidBodySpec& body : spec.value().rigid_bodies) {
        EXPECT_TRUE(body.pose.origin.allFinite()) << k;
        EXPECT_NEAR(body.pose.rotation.norm(), 1.0, 1e-9) << k;
      }
    } else {
      ++refused;
      if (contains(spec.error().message, "crashed")) ++crashed_reader;
      EXPECT_TRUE(contains(spec.error().message, "b.json: bullet_file: " + path + ": "))
          << k << ": " << spec.error().message;
    }
  }
  std::cout << "[figures] 300 corrupted .bullet files: " << refused << " refused ("
            << crashed_reader << " of them crashed Bullet's reader in its child process), "
            << loaded << " loaded and checked\n";
  EXPECT_GT(refused, 0);
  EXPECT_GT(crashed_reader, 0) << "no corruption reached a crash: the test no longer shows the "
                                  "isolation";
}

TEST(BulletFileImport, NamesInTheFileGoThroughTheSceneNameChecks) {
  {
    SerializedWorld w;
    w.add(box(0.1), 1, btVector3(0, 0, 1), "../escape");
    Result<SceneSpec> spec = parseWith(writeTemp("escape", w.bytes())->path);
    ASSERT_FALSE(spec.ok());
    EXPECT_TRUE(contains(spec.error().message, "rigid_bodies[0].name")) << spec.error().message;
  }
  {
    SerializedWorld w;
    w.add(box(0.1), 1, btVector3(0, 0, 1), "box");
    w.add(box(0.1), 1, btVector3(0, 0, 2), "box");
    Result<SceneSpec> spec = parseWith(writeTemp("twice", w.bytes())->path);
    ASSERT_FALSE(spec.ok());
    EXPECT_TRUE(contains(spec.error().message, "duplicate rigid body name 'box'"))
        << spec.error().message;
  }
  {
    // FEM body "rigid_box" and rigid body "box" would write the same series files.
    SerializedWorld w;
    w.add(box(0.1), 1, btVector3(0, 0, 1), "box");
    Result<SceneSpec> spec = parseWith(writeTemp("series", w.bytes())->path, "rigid_box");
    ASSERT_FALSE(spec.ok());
    EXPECT_TRUE(contains(spec.error().message, "same series files")) << spec.error().message;
  }
}

TEST(BulletFileImport, ConstraintsAndShapesASceneCannotDescribeAreRefusedNamingThem) {
  {
    SerializedWorld w;
    btRigidBody* a = w.add(box(0.1), 1, btVector3(0, 0, 1));
    btRigidBody* b = w.add(box(0.1), 1, btVector3(0, 0, 2));
    w.constraints.push_back(std::make_unique<btPoint2PointConstraint>(
        *a, *b, btVector3(0, 0, btScalar(0.5)), btVector3(0, 0, btScalar(-0.5))));
    w.world.addConstraint(w.constraints.back().get());
    Result<SceneSpec> spec = parseWith(writeTemp("constraint", w.bytes())->path);
    ASSERT_FALSE(spec.ok());
    EXPECT_TRUE(contains(spec.error().message, "1 constraint(s)")) << spec.error().message;
  }
  {
    SerializedWorld w;
    w.add(
        std::make_unique<btCylinderShapeZ>(btVector3(btScalar(0.1), btScalar(0.1), btScalar(0.2))),
        1, btVector3(0, 0, 1), "can");
    Result<SceneSpec> spec = parseWith(writeTemp("cylinder", w.bytes())->path);
    ASSERT_FALSE(spec.ok());
    EXPECT_TRUE(contains(spec.error().message, "rigid body 0 (\"can\"): its shape is a CylinderZ"))
        << spec.error().message;
  }
  {
    // A body with a mass the scene refuses (Bullet's impulses would overflow).
    SerializedWorld w;
    w.add(box(0.1), 1e-30, btVector3(0, 0, 1), "feather");
    Result<SceneSpec> spec = parseWith(writeTemp("feather", w.bytes())->path);
    ASSERT_FALSE(spec.ok());
    EXPECT_TRUE(contains(spec.error().message, "rigid_bodies[0].mass")) << spec.error().message;
  }
}

// runIsolated itself: the child's answer comes back byte for byte; its error, crash, hang and
// hunger for memory come back as errors saying which.
TEST(IsolatedCall, TheChildsAnswerErrorCrashHangAndMemoryComeBackAsSuch) {
  const std::string bytes("a\0b\xff", 4);
  Result<std::string> answer = runIsolated([&] { return Result<std::string>(bytes); }, "work");
  ASSERT_TRUE(answer.ok()) << answer.error().message;
  EXPECT_EQ(answer.value(), bytes);

  Result<std::string> refused =
      runIsolated([] { return Result<std::string>(Error{"no good"}); }, "work");
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().message, "no good");

  Result<std::string> crashed = runIsolated(
      []() -> Result<std::string> {
        std::raise(SIGSEGV);
        return std::string();
      },
      "work");
  ASSERT_FALSE(crashed.ok());
  EXPECT_TRUE(contains(crashed.error().message, "work crashed (signal 11"))
      << crashed.error().message;
  // A sanitizer's report (here: writes past a buffer, under ASan) ends the child with status 1;
  // without a sanitizer the same fault ends as a crash by signal or goes unseen. Either way this
  // process answers.
  Result<std::string> scribbled = runIsolated(
      []() -> Result<std::string> {
        std::vector<char> small(4);
        volatile char* p = small.data();
        for (int i = 0; i < (1 << 24); ++i)
          p[i] = 1;
        return Error{"the writes went unseen"};
      },
      "work");
  ASSERT_FALSE(scribbled.ok());
  EXPECT_TRUE(contains(scribbled.error().message, "work crashed (") ||
              scribbled.error().message == "the writes went unseen")
      << scribbled.error().message;

  IsolationLimits quick;
  quick.wall_seconds = 0.5;
  const auto start = std::chrono::steady_clock::now();
  Result<std::string> hung = runIsolated(
      []() -> Result<std::string> {
        for (;;)
          std::this_thread::sleep_for(std::chrono::seconds(1));
      },
      "work", quick);
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_FALSE(hung.ok());
  EXPECT_EQ(hung.error().message, "work did not finish within 0.5 s");
  EXPECT_LT(waited, 5.0);  // killed, not waited for

#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__) && \
    !(defined(__has_feature) && __has_feature(address_sanitizer))
  IsolationLimits small;
  small.memory_bytes = std::size_t{64} << 20;
  Result<std::string> hungry = runIsolated(
      []() -> Result<std::string> {
        std::vector<char> lots(std::size_t{1} << 30, 1);
        return std::string(1, lots.back());
      },
      "work", small);
  ASSERT_FALSE(hungry.ok());
  EXPECT_EQ(hungry.error().message, "work needed more than 64 MiB of memory");
#endif
}

}  // namespace
}  // namespace torsion::scene
