// Checkpoints as bytes (bullet/checkpoint_io.h): read back into the same world or one built the
// same way, they continue bit for bit; truncated, altered or foreign bytes are refused, never read
// out of bounds (this test runs under ASan with the unit label).
#include "torsion/bullet/checkpoint_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string_view>
#include <vector>

#include "checkpoint_rigs.h"
#include "torsion/fnv1a.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

// A block dropped onto a static slab (rigid contact with warm starts), grabbed on its top by a
// hand after the world was built and turned about z.
class BlockRig {
 public:
  BlockRig() : world_(test::checkpointWorldSettings()) {
    Material material;
    material.youngs_modulus = 2e4;
    body_ =
        world_
            .addBody("block", makeBoxTetMesh({-0.2, -0.2, 0.02}, {0.2, 0.2, 0.42}, 2, 2, 2).value(),
                     material)
            .value();
    btTransform slab;
    slab.setIdentity();
    slab.setOrigin(btVector3(0, 0, btScalar(-0.5)));
    world_.addRigidBody(std::make_unique<btBoxShape>(btVector3(2, 2, btScalar(0.5))), 0.0, slab);
    hand_ = std::make_unique<Hand>(*body_);
  }

  void step() {
    const double t = world_.time();
    if (t > 0.25 && !hand_->grabbed()) {
      ASSERT_TRUE(
          hand_->grab(Frame{Eigen::Vector3d(0, 0, 0.3), Eigen::Quaterniond::Identity()}, t).ok());
    }
    if (hand_->grabbed()) {
      const Eigen::Quaterniond turn(Eigen::AngleAxisd(t - 0.25, Eigen::Vector3d::UnitZ()));
      ASSERT_TRUE(hand_->moveTo(Frame{Eigen::Vector3d(0, 0, 0.3), turn}).ok());
    }
    const WorldStepReport r = world_.step();
    ASSERT_TRUE(r.ok) << r.message;
  }

  std::string save() { return test::saveBytes(world_, {hand_.get()}, "x"); }
  Status load(const std::string& bytes) { return test::loadBytes(bytes, world_, {hand_.get()}); }

  FemWorld world_;
  FemBody* body_;
  std::unique_ptr<Hand> hand_;
};

constexpr size_t kHeader = 28;  // magic, version, length, hash

std::uint64_t payloadHash(const std::string& bytes) {
  return fnv1a(std::string_view(bytes).substr(kHeader));
}

// Saved after 40 steps, the world goes on 20; a world built the same way and read from the bytes
// must take the same 20 steps to the bit (the contacts' warm starts included: their impulses,
// the next step's friction bounds).
TEST(CheckpointIo, BytesReadIntoANewWorldContinueBitForBitWithContactsAndAGrab) {
  BlockRig rig;
  for (int k = 0; k < 40; ++k)
    rig.step();
  ASSERT_FALSE(rig.body_->contacts().contacts().empty()) << "the block must rest on the slab";
  ASSERT_TRUE(rig.hand_->grabbed());
  const std::string bytes = rig.save();
  for (int k = 0; k < 20; ++k)
    rig.step();

  BlockRig fresh;  // built the same way, never stepped, nothing grabbed
  ASSERT_TRUE(fresh.load(bytes).ok());
  EXPECT_TRUE(fresh.hand_->grabbed());
  for (int k = 0; k < 20; ++k)
    fresh.step();
  EXPECT_EQ(fresh.world_.stepCount(), rig.world_.stepCount());
  EXPECT_EQ((fresh.body_->state().positions - rig.body_->state().positions).cwiseAbs().maxCoeff(),
            0.0);
  EXPECT_EQ(fresh.hand_->wrench().torque, rig.hand_->wrench().torque);
  EXPECT_GT(rig.hand_->wrench().torque.norm(), 1e-4) << "the block must be twisted";
}

// A dynamic box resting on a soft slab, solved by the convex solve: its face rows (the box's
// corners and edges) start each step from the last step's normal impulses, which the bytes carry
// (CarriedContacts::features). Saved after 40 steps, read into a world built the same way, the
// next 20 steps match to the bit, box and slab.
TEST(CheckpointIo, BytesCarryTheConvexSolvesFaceRowsAndContinueBitForBit) {
  struct BoxRig {
    BoxRig() : world(test::checkpointWorldSettings()) {
      Material material;
      material.youngs_modulus = 5e4;
      slab = world
                 .addBody("slab", makeBoxTetMesh({-0.3, -0.3, 0}, {0.3, 0.3, 0.1}, 5, 5, 2).value(),
                          material)
                 .value();
      test::holdBase(*slab);
      btTransform pose;
      pose.setIdentity();
      pose.setOrigin(btVector3(btScalar(0.02), 0, btScalar(0.2)));
      box = world.addRigidBody(std::make_unique<btBoxShape>(btVector3(0.1, 0.1, 0.1)), 1.0, pose);
    }
    void step() {
      const WorldStepReport r = world.step();
      ASSERT_TRUE(r.ok) << r.message;
    }
    FemWorld world;
    FemBody* slab;
    btRigidBody* box;
  };
  BoxRig rig;
  for (int k = 0; k < 40; ++k)
    rig.step();
  ASSERT_FALSE(rig.slab->contacts().carriedContacts().features.empty())
      << "the box must rest on its corners or edges too";
  const std::string bytes = test::saveBytes(rig.world, {});
  for (int k = 0; k < 20; ++k)
    rig.step();
  BoxRig fresh;
  ASSERT_TRUE(test::loadBytes(bytes, fresh.world, {}).ok());
  for (int k = 0; k < 20; ++k)
    fresh.step();
  EXPECT_EQ((fresh.slab->state().positions - rig.slab->state().positions).cwiseAbs().maxCoeff(),
            0.0);
  EXPECT_EQ(fresh.box->getCenterOfMassPosition(), rig.box->getCenterOfMassPosition());
  EXPECT_EQ(fresh.box->getLinearVelocity(), rig.box->getLinearVelocity());
}

TEST(CheckpointIo, TruncatedForeignOrAlteredBytesAreRefusedWithTheirReason) {
  BlockRig rig;
  for (int k = 0; k < 40; ++k)
    rig.step();
  const std::string bytes = rig.save();
  for (size_t n = 0; n < bytes.size(); ++n) {
    Status loaded = rig.load(bytes.substr(0, n));
    ASSERT_FALSE(loaded.ok()) << n;
  }
  EXPECT_NE(rig.load("GIF89a...").error().message.find("not a torsion checkpoint"),
            std::string::npos);
  std::string altered = bytes;
  altered[bytes.size() / 2] ^= 0x04;
  EXPECT_NE(rig.load(altered).error().message.find("corrupted"), std::string::npos);
  EXPECT_TRUE(rig.load(bytes).ok());
}

// A checkpoint in memory keeps the contact solvers' memory as the bytes a file stores
// (FemBodyCheckpoint::contacts). Those bytes cut short, or naming a rigid object the world does not
// have, are refused naming the body and the part being read, in memory as from a file, and the
// world is left as it was.
TEST(CheckpointIo, ContactBytesCutShortOrNamingNoObjectAreRefusedNamingThem) {
  BlockRig rig;
  for (int k = 0; k < 40; ++k)
    rig.step();
  ASSERT_FALSE(rig.body_->contacts().carriedContacts().nodes.empty())
      << "the block must rest on the slab";
  const double time = rig.world_.time();
  const WorldCheckpoint saved = rig.world_.checkpoint();
  const std::string& contacts = saved.fem.bodies.front().second.contacts;
  EXPECT_NE(rig.save().find(contacts), std::string::npos) << "a file holds the same bytes";

  const auto refusals = [&](const std::string& altered) {
    WorldCheckpoint c = saved;
    c.fem.bodies.front().second.contacts = altered;
    const Status restored = rig.world_.restore(c);
    EXPECT_EQ(rig.world_.time(), time) << "a refused checkpoint changes nothing";
    std::vector<HandCheckpoint> hands{rig.hand_->checkpoint()};
    const std::string bytes = writeCheckpoint(rig.world_, c, {rig.hand_.get()}, hands, "");
    Result<StoredCheckpoint> read = readCheckpoint(bytes, rig.world_, {rig.hand_.get()});
    return std::pair<std::string, std::string>{
        restored.ok() ? "(restored)" : restored.error().message,
        read.ok() ? "(read)" : read.error().message};
  };
  const auto [cut_in_memory, cut_in_file] = refusals(contacts.substr(0, contacts.size() - 1));
  EXPECT_EQ(cut_in_memory,
            "restore: the checkpoint is truncated or corrupted (reading body 'block': its rigid "
            "contacts)");
  EXPECT_EQ(cut_in_file,
            "the checkpoint is truncated or corrupted (reading body 'block': its rigid contacts)");

  // After the friction (f64), the count of node contacts (u32) and the first one's node (i32):
  // its rigid object's index among the world's collision objects (the block and the slab).
  std::string elsewhere = contacts;
  const std::int32_t absent = 7;
  elsewhere.replace(16, 4, reinterpret_cast<const char*>(&absent), 4);
  const auto [absent_in_memory, absent_in_file] = refusals(elsewhere);
  const std::string why =
      "the checkpoint holds an invalid value: rigid object 7 (the world has 2 collision objects) "
      "(reading body 'block': its rigid contacts)";
  EXPECT_EQ(absent_in_memory, "restore: " + why);
  EXPECT_EQ(absent_in_file, why);
  ASSERT_TRUE(rig.world_.restore(saved).ok()) << "the bytes as saved still restore";
}

// The published FNV-1a 64 test vectors (the IETF draft's), so that anyone can check a
// checkpoint's hash with a standard implementation; the header carries exactly that hash of the
// payload.
TEST(CheckpointIo, TheHashIsTheStandardFnv1aOfThePayload) {
  EXPECT_EQ(fnv1a(""), 0xcbf29ce484222325ull);
  EXPECT_EQ(fnv1a("a"), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a("foobar"), 0x85944171f73967e8ull);
  BlockRig rig;
  rig.step();
  const std::string bytes = rig.save();
  ASSERT_GT(bytes.size(), kHeader);
  std::uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + 20, sizeof stored);
  EXPECT_EQ(stored, payloadHash(bytes));
}

// Bytes crafted behind a valid hash (the hash only catches accidents) that carry values no save
// writes are refused naming what is wrong, and the world is left as it was: a NaN or negative
// clock, a step count of -1, a hand frame whose quaternion is not unit.
std::string withValidHash(std::string bytes) {
  const std::uint64_t hash = payloadHash(bytes);
  bytes.replace(20, 8, reinterpret_cast<const char*>(&hash), 8);
  return bytes;
}

template <typename T>
std::string withValueAt(const std::string& bytes, size_t at, T value) {
  std::string altered = bytes;
  altered.replace(at, sizeof(T), reinterpret_cast<const char*>(&value), sizeof(T));
  return withValidHash(altered);
}

TEST(CheckpointIo, CraftedValuesBehindAValidHashAreRefusedNamingTheValue) {
  BlockRig rig;
  for (int k = 0; k < 40; ++k)
    rig.step();
  ASSERT_TRUE(rig.hand_->grabbed());
  const std::string bytes = rig.save();
  const double time = rig.world_.time();
  const auto expectRefused = [&](const std::string& altered, const std::string& what) {
    const Status loaded = rig.load(altered);
    ASSERT_FALSE(loaded.ok()) << what;
    EXPECT_NE(loaded.error().message.find("holds an invalid value: " + what), std::string::npos)
        << loaded.error().message;
    EXPECT_EQ(rig.world_.time(), time) << "a refused checkpoint changes nothing";
  };
  // The payload starts with the clock: time (f64), steps (i64), last step (f64).
  expectRefused(withValueAt(bytes, kHeader, std::nan("")), "the clock");
  expectRefused(withValueAt(bytes, kHeader, -1.0), "the clock");
  expectRefused(withValueAt(bytes, kHeader + 8, std::int64_t{-1}), "the clock");
  expectRefused(withValueAt(bytes, kHeader + 16, std::numeric_limits<double>::infinity()),
                "the clock");

  // The hand's frames: the bytes of its patch frame's quaternion (x, y, z, w), wherever they are
  // stored, scaled by 2.
  const Eigen::Quaterniond q = rig.hand_->frame().rotation;
  std::string pattern;
  for (const double c : {q.x(), q.y(), q.z(), q.w()})
    pattern.append(reinterpret_cast<const char*>(&c), sizeof c);
  std::string scaled = bytes;
  int found = 0;
  for (size_t at = scaled.find(pattern, kHeader); at != std::string::npos;
       at = scaled.find(pattern, at + pattern.size())) {
    for (int k = 0; k < 4; ++k) {
      double c = 0;
      std::memcpy(&c, scaled.data() + at + 8 * k, sizeof c);
      c *= 2;
      std::memcpy(scaled.data() + at + 8 * k, &c, sizeof c);
    }
    ++found;
  }
  ASSERT_GT(found, 0) << "the hand's frame must be in the bytes";
  expectRefused(withValidHash(scaled), "a frame");

  ASSERT_TRUE(rig.load(bytes).ok()) << "the bytes as saved still load";
}

TEST(CheckpointIo, BytesAlteredBehindAValidHashAreRefusedOrReadNeverOutOfBounds) {
  BlockRig rig;
  for (int k = 0; k < 40; ++k)
    rig.step();
  const std::string bytes = rig.save();
  std::mt19937 random(11);
  int refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string altered = bytes;
    for (int k = 0; k < 3; ++k) {
      const size_t at = kHeader + random() % (bytes.size() - kHeader);
      altered[at] = static_cast<char>(random() % 256);
    }
    const std::uint64_t hash = payloadHash(altered);
    altered.replace(20, 8, reinterpret_cast<const char*>(&hash), 8);
    if (!rig.load(altered).ok()) {
      ++refused;
      continue;
    }
    (void)rig.world_.step();  // garbage numbers may fail the step; they must not crash it
  }
  EXPECT_GT(refused, 0);
}

TEST(CheckpointIo, AnotherWorldIsNamedAsSuch) {
  BlockRig rig;
  rig.step();
  const std::string bytes = rig.save();
  FemWorld other(test::checkpointWorldSettings());
  FemBody* body =
      other
          .addBody("block", makeBoxTetMesh({-0.2, -0.2, 0.02}, {0.2, 0.2, 0.42}, 3, 3, 3).value(),
                   Material{})
          .value();
  Hand hand(*body);
  Result<StoredCheckpoint> read = readCheckpoint(bytes, other, {&hand});
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.error().message.find("saved from another world: body 'block' has another mesh"),
            std::string::npos)
      << read.error().message;
}

// A world like the rig's but for one difference, which the refusal must name.
struct OtherWorld {
  OtherWorld() : world(test::checkpointWorldSettings()) {}
  FemBody* add(const std::string& name, double x = 0) {
    Material material;
    material.youngs_modulus = 2e4;
    return world
        .addBody(name, makeBoxTetMesh({x - 0.2, -0.2, 0.02}, {x + 0.2, 0.2, 0.42}, 2, 2, 2).value(),
                 material)
        .value();
  }
  FemWorld world;
};

std::string refusal(const std::string& bytes, FemWorld& world, const std::vector<Hand*>& hands) {
  Result<StoredCheckpoint> read = readCheckpoint(bytes, world, hands);
  return read.ok() ? std::string("(read)") : read.error().message;
}

TEST(CheckpointIo, AnotherWorldsCheckpointInMemoryIsRefusedAsSuch) {
  BlockRig rig;
  rig.step();
  OtherWorld other;  // the rig's block and slab, but another world's
  other.add("block");
  btTransform slab;
  slab.setIdentity();
  slab.setOrigin(btVector3(0, 0, btScalar(-0.5)));
  other.world.addRigidBody(std::make_unique<btBoxShape>(btVector3(2, 2, btScalar(0.5))), 0.0, slab);
  const Status restored = other.world.restore(rig.world_.checkpoint());
  ASSERT_FALSE(restored.ok());
  EXPECT_NE(restored.error().message.find("not in this world (removed since, or the checkpoint is "
                                          "another world's"),
            std::string::npos)
      << restored.error().message;
}

TEST(CheckpointIo, AWorldWithoutTheHandIsToldTheHandItLacks) {
  BlockRig rig;
  rig.step();
  OtherWorld other;
  other.add("block");
  EXPECT_EQ(refusal(rig.save(), other.world, {}),
            "the checkpoint was saved from another world: it has 1 hand (the first 'hand' on "
            "body 'block'), this world none");
}

TEST(CheckpointIo, AWorldWithAHandOrABodyTheCheckpointLacksIsToldWhich) {
  FemWorld empty(test::checkpointWorldSettings());
  const std::string nothing = test::saveBytes(empty, {});
  OtherWorld other;
  FemBody* block = other.add("block");
  EXPECT_EQ(refusal(nothing, other.world, {}),
            "the checkpoint was saved from another world: it has no FEM body, this world 'block'");
  OtherWorld plain;
  plain.add("block");
  const std::string handless = test::saveBytes(plain.world, {});
  Hand hand(*block);
  EXPECT_EQ(refusal(handless, other.world, {&hand}),
            "the checkpoint was saved from another world: it has no hand, this world 1 hand: "
            "'hand' on body 'block'");
}

TEST(CheckpointIo, AWorldWithAnExtraBodyIsToldWhichBody) {
  BlockRig rig;
  rig.step();
  OtherWorld other;
  FemBody* block = other.add("block");
  other.add("extra", 2.0);
  Hand hand(*block);
  EXPECT_EQ(refusal(rig.save(), other.world, {&hand}),
            "the checkpoint was saved from another world: it has 1 FEM body: 'block'; this "
            "world also has 'extra'");
}

TEST(CheckpointIo, AWorldWithoutASavedBodyIsToldItsNameAndItsOwnBodies) {
  BlockRig rig;
  rig.step();
  OtherWorld other;
  FemBody* cube = other.add("cube");
  Hand hand(*cube, "hand");
  EXPECT_EQ(refusal(rig.save(), other.world, {&hand}),
            "the checkpoint was saved from another world: its hand 0 is 'hand' on body 'block', "
            "here 'hand' on body 'cube'");
  OtherWorld handless;
  handless.add("cube");
  BlockRig plain;
  const std::string bytes = test::saveBytes(plain.world_, {}, "x");
  EXPECT_EQ(refusal(bytes, handless.world, {}),
            "the checkpoint was saved from another world: its body 'block' is not in this world "
            "(1 FEM body: 'cube')");
}

}  // namespace
}  // namespace torsion

namespace torsion {
namespace {

// A soft block resting on a soft slab (base fixed): contact between FEM bodies, whose multipliers
// warm-start every step.
class TouchingBodiesRig {
 public:
  TouchingBodiesRig() : world_(test::checkpointWorldSettings()) {
    Material material;
    material.youngs_modulus = 5e4;
    slab_ = world_
                .addBody("slab", makeBoxTetMesh({-0.2, -0.2, 0}, {0.2, 0.2, 0.1}, 2, 2, 1).value(),
                         material)
                .value();
    test::holdBase(*slab_);
    block_ = world_
                 .addBody("block",
                          makeBoxTetMesh({-0.08, -0.05, 0.101}, {0.06, 0.07, 0.2}, 2, 2, 2).value(),
                          material)
                 .value();
  }

  std::string save() { return test::saveBytes(world_, {}); }
  Status load(const std::string& bytes) { return test::loadBytes(bytes, world_, {}); }
  void steps(int n) {
    for (int k = 0; k < n; ++k) {
      const WorldStepReport r = world_.step();
      ASSERT_TRUE(r.ok) << r.message;
    }
  }
  double difference(const TouchingBodiesRig& other) const {
    return std::max(
        (block_->state().positions - other.block_->state().positions).cwiseAbs().maxCoeff(),
        (slab_->state().velocities - other.slab_->state().velocities).cwiseAbs().maxCoeff());
  }

  FemWorld world_;
  FemBody* slab_;
  FemBody* block_;
};

TEST(CheckpointIo, BytesTakenWhileTwoFemBodiesTouchContinueBitForBitWithTheirPairMultipliers) {
  TouchingBodiesRig rig;
  rig.steps(30);
  const BodyPairContact* pair = rig.world_.femSolver().femContact()->pair(rig.slab_, rig.block_);
  ASSERT_NE(pair, nullptr);
  ASSERT_FALSE(pair->set().warmStarts().empty()) << "the block must rest on the slab";
  const std::string bytes = rig.save();
  rig.steps(15);

  TouchingBodiesRig fresh;  // built the same way, never stepped
  ASSERT_TRUE(fresh.load(bytes).ok());
  fresh.steps(15);
  EXPECT_EQ(fresh.difference(rig), 0.0);

  // The same world, back to the bytes after stepping on: the pairs it kept since are replaced.
  ASSERT_TRUE(rig.load(bytes).ok());
  rig.steps(15);
  EXPECT_EQ(fresh.difference(rig), 0.0);
}

}  // namespace
}  // namespace torsion
