#include "viewer.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <sstream>
#include <vector>

#include "camera.h"
#include "frame_data.h"
#include "image.h"
#include "manual_tool.h"
#include "pacing.h"
#include "renderer.h"
#include "scene_builder.h"
#include "scene_haptics.h"
#include "scene_parser.h"
#include "torsion/bt_conversions.h"
#include "viewer_window.h"

namespace torsion::viewer {

namespace {

using render::Camera;

// The linear solvers the C key steps through, in order of cost per iteration: CG with each
// preconditioner, then CHOLMOD. `two_level` is left out on tet4, where it is lagged_cholesky.
struct SolverChoice {
  LinearSolverKind solver;
  PreconditionerKind preconditioner;
};
constexpr SolverChoice kSolverCycle[] = {
    {LinearSolverKind::kConjugateGradient, PreconditionerKind::kJacobi},
    {LinearSolverKind::kConjugateGradient, PreconditionerKind::kBlockJacobi},
    {LinearSolverKind::kConjugateGradient, PreconditionerKind::kIncompleteCholesky},
    {LinearSolverKind::kConjugateGradient, PreconditionerKind::kLaggedCholesky},
    {LinearSolverKind::kConjugateGradient, PreconditionerKind::kTwoLevel},
    {LinearSolverKind::kCholmod, PreconditionerKind::kBlockJacobi},
};

// Moves `s` by `direction` (+1 or -1) along kSolverCycle; a choice not in it counts as the first.
void cycleLinearSolver(SolverSettings& s, int direction) {
  constexpr int n = static_cast<int>(std::size(kSolverCycle));
  int at = 0;
  for (int i = 0; i < n; ++i) {
    const SolverChoice& c = kSolverCycle[i];
    const bool cholmod = s.linear_solver == LinearSolverKind::kCholmod;
    if (c.solver == s.linear_solver && (cholmod || c.preconditioner == s.preconditioner)) at = i;
  }
  const SolverChoice& next = kSolverCycle[((at + direction) % n + n) % n];
  s.linear_solver = next.solver;
  s.preconditioner = next.preconditioner;
}

// One input event, from GLFW or from a script line "<frame> key NAME [shift]",
// "<frame> drag left|right|middle DX DY [ctrl]", "<frame> scroll DY".
struct InputEvent {
  int frame = 0;
  enum class Kind { kKey, kDrag, kScroll } kind = Kind::kKey;
  int key = 0;
  bool shift = false, ctrl = false;
  int button = 0;  // GLFW_MOUSE_BUTTON_*
  double dx = 0, dy = 0;
};

int keyFromName(const std::string& name) {
  static const std::pair<const char*, int> kNamed[] = {
      {"SPACE", GLFW_KEY_SPACE},    {"ESCAPE", GLFW_KEY_ESCAPE},
      {"LEFT", GLFW_KEY_LEFT},      {"RIGHT", GLFW_KEY_RIGHT},
      {"UP", GLFW_KEY_UP},          {"DOWN", GLFW_KEY_DOWN},
      {"PAGEUP", GLFW_KEY_PAGE_UP}, {"PAGEDOWN", GLFW_KEY_PAGE_DOWN}};
  for (const auto& [n, k] : kNamed) {
    if (name == n) return k;
  }
  if (name.size() == 1 && std::isalpha(static_cast<unsigned char>(name[0])))
    return GLFW_KEY_A + (std::toupper(static_cast<unsigned char>(name[0])) - 'A');
  return -1;
}

Result<std::vector<InputEvent>> readScript(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Error{path + ": cannot open the input script"};
  std::vector<InputEvent> events;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line);
    InputEvent e;
    std::string kind;
    if (!(words >> e.frame) || line.empty() || line[0] == '#') {
      if (line.find_first_not_of(" \t") == std::string::npos || line[0] == '#') continue;
      return Error{path + ":" + std::to_string(number) + ": expected '<frame> <event> ...'"};
    }
    words >> kind;
    std::string extra;
    if (kind == "key") {
      std::string name;
      words >> name;
      e.key = keyFromName(name);
      if (e.key < 0) return Error{path + ":" + std::to_string(number) + ": unknown key " + name};
      e.shift = (words >> extra) && extra == "shift";
    } else if (kind == "drag") {
      std::string button;
      words >> button >> e.dx >> e.dy;
      e.kind = InputEvent::Kind::kDrag;
      e.button = button == "left"    ? GLFW_MOUSE_BUTTON_LEFT
                 : button == "right" ? GLFW_MOUSE_BUTTON_RIGHT
                                     : GLFW_MOUSE_BUTTON_MIDDLE;
      e.ctrl = (words >> extra) && extra == "ctrl";
      if (!words.eof() && words.fail())
        return Error{path + ":" + std::to_string(number) + ": drag wants BUTTON DX DY [ctrl]"};
    } else if (kind == "scroll") {
      words >> e.dy;
      e.kind = InputEvent::Kind::kScroll;
    } else {
      return Error{path + ":" + std::to_string(number) + ": unknown event '" + kind + "'"};
    }
    events.push_back(e);
  }
  return events;
}

// A frame as origin and rotation vector (angle times axis of R = [i j k]), for the exit report.
std::string poseText(const Frame& f) {
  const Eigen::AngleAxisd turn(f.rotation);
  const Eigen::Vector3d r = turn.angle() * turn.axis();
  char buf[160];
  std::snprintf(buf, sizeof buf, "at (%.6g, %.6g, %.6g) m turned (%.6g, %.6g, %.6g) rad",
                f.origin.x(), f.origin.y(), f.origin.z(), r.x(), r.y(), r.z());
  return buf;
}

class Viewer : public InputSink {
 public:
  Viewer(const ViewerOptions& options, scene::SceneSpec spec)
      : options_(options), spec_(std::move(spec)) {}

  Status rebuild() {
    scene::BuildOptions build;
    build.threads = options_.threads;
    build.manual_devices = true;  // this viewer's input moves them
    auto built = scene::buildScene(spec_, build);
    if (!built) return built.error();
    tool_.reset();  // its device goes with the old scene
    scene_ = std::move(built).value();
    if (scene_->haptics) {
      if (auto manual = scene_->haptics->manualTool()) tool_.emplace(*manual);
    }
    manual_ = false;
    unstable_.clear();
    history_ = render::WrenchHistory{};
    return Ok{};
  }

  void frameAll(int width, int height) {
    const render::FrameData f = frame();
    camera_ = render::frameCamera(
        f, double(render::sceneViewportWidth(width, height, {})) / std::max(1, height),
        render::hudHeightFraction(f, height, {}));
  }

  // ---- input ----
  void onKey(int key, bool shift) override {
    const double size = sceneSize();
    const double step = 0.05 * size, angle = 5 * M_PI / 180;
    const Eigen::Vector3d axis =
        key == GLFW_KEY_LEFT || key == GLFW_KEY_RIGHT ? Eigen::Vector3d::UnitX()
        : key == GLFW_KEY_UP || key == GLFW_KEY_DOWN  ? Eigen::Vector3d::UnitY()
                                                      : Eigen::Vector3d::UnitZ();
    const double sign =
        key == GLFW_KEY_RIGHT || key == GLFW_KEY_UP || key == GLFW_KEY_PAGE_UP ? 1.0 : -1.0;
    switch (key) {
      case GLFW_KEY_ESCAPE:
      case GLFW_KEY_Q:
        quit_ = true;
        break;
      case GLFW_KEY_SPACE:
        paused_ = !paused_;
        break;
      case GLFW_KEY_N:
        single_step_ = true;
        break;
      case GLFW_KEY_R:
        reset();
        break;
      case GLFW_KEY_F:
        reframe_ = true;
        break;
      case GLFW_KEY_M:
        toggleManual();
        break;
      case GLFW_KEY_G:
        if (toolHasKeys()) {
          holdToolButton(true);
        } else {
          grab();
        }
        break;
      case GLFW_KEY_U:
        if (toolHasKeys()) {
          holdToolButton(false);
        } else if (manual_ && hand()) {
          hand()->hand->release();
        }
        break;
      case GLFW_KEY_LEFT:
      case GLFW_KEY_RIGHT:
      case GLFW_KEY_UP:
      case GLFW_KEY_DOWN:
      case GLFW_KEY_PAGE_UP:
      case GLFW_KEY_PAGE_DOWN:
        moveManual([&](Frame& f) {
          if (shift) {
            f.rotation = (Eigen::AngleAxisd(sign * angle, axis) * f.rotation).normalized();
          } else {
            f.origin += sign * step * axis;
          }
        });
        break;
      case GLFW_KEY_T:
        editSolver([&](SolverSettings& s) { s.time_step *= shift ? 0.5 : 2.0; });
        break;
      case GLFW_KEY_E:
        editMaterial([&](Material& m) { m.youngs_modulus *= shift ? 1 / 1.5 : 1.5; });
        break;
      case GLFW_KEY_P:
        editMaterial([&](Material& m) {
          m.poisson_ratio = std::clamp(m.poisson_ratio + (shift ? -0.02 : 0.02), 0.0, 0.48);
        });
        break;
      case GLFW_KEY_D:
        editMaterial([&](Material& m) { m.stiffness_damping *= shift ? 0.5 : 2.0; });
        break;
      case GLFW_KEY_C:
        editSolver([&](SolverSettings& s) { cycleLinearSolver(s, shift ? -1 : 1); });
        break;
      default:
        break;
    }
  }

  // dx, dy in pixels of a window `height` pixels high.
  void onDrag(int button, double dx, double dy, bool ctrl, int height) override {
    if (ctrl && button == GLFW_MOUSE_BUTTON_LEFT) {
      const Eigen::Matrix4d v = camera_.view();
      const double visible = 2 * camera_.distance * std::tan(camera_.fov_y / 2);
      const Eigen::Vector3d shift =
          visible / std::max(1, height) *
          (dx * v.block<1, 3>(0, 0).transpose() - dy * v.block<1, 3>(1, 0).transpose());
      moveManual([&](Frame& f) { f.origin += shift; });
    } else {
      dragCamera(camera_, button, dx, dy, height);
    }
  }

  void onScroll(double dy) override { scrollCamera(camera_, dy); }

  void apply(const InputEvent& e, int height) {
    switch (e.kind) {
      case InputEvent::Kind::kKey:
        onKey(e.key, e.shift);
        break;
      case InputEvent::Kind::kDrag:
        onDrag(e.button, e.dx, e.dy, e.ctrl, height);
        break;
      case InputEvent::Kind::kScroll:
        onScroll(e.dy);
        break;
    }
  }

  // ---- simulation ----
  /// One frame's steps, `elapsed` s of wall time after the previous frame's: --steps-per-frame
  /// of them, or as many as keep simulated time on the wall clock (pacing.h); none while paused
  /// (N: one).
  void advanceFrame(double elapsed) {
    if (!unstable_.empty()) return;
    if (paused_ || options_.steps_per_frame > 0) {
      lag_ = 0;
      const int steps = paused_ ? (single_step_ ? 1 : 0) : options_.steps_per_frame;
      for (int i = 0; i < steps && unstable_.empty(); ++i)
        advance();
      return;
    }
    PacingInput in;
    in.dt = scene_->world->settings().solver.time_step;
    in.elapsed = elapsed;
    in.step_cost = step_cost_;
    in.lag = lag_;
    const PacingDecision d = paceFrame(in);
    for (int i = 0; i < d.steps && unstable_.empty(); ++i)
      advance();
    lag_ = d.lag;
    // The HUD's factor over the last second or so of frames, so it reads steadily.
    shown_factor_ += 0.1 * (d.real_time_factor - shown_factor_);
  }

  void advance() {
    if (!unstable_.empty()) return;
    if (paused_ && !single_step_) return;
    single_step_ = false;
    Status driven = scene::driveHands(*scene_);
    if (!driven) {
      unstable_ = driven.error().message;
      return;
    }
    if (manual_ && hand() && hand()->hand->grabbed()) {
      if (Status moved = hand()->hand->moveTo(manual_frame_); !moved) {
        unstable_ = moved.error().message;
        return;
      }
    }
    // A threaded haptic loop waits for the step's wall-clock time: outside its measured cost.
    if (scene_->haptics) scene_->haptics->pace();
    const auto t0 = std::chrono::steady_clock::now();
    // Device hands (if any) step through their haptic loops.
    const WorldStepReport r = scene_->haptics ? scene_->haptics->step() : scene_->world->step();
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    rate_ = seconds > 0 ? 0.9 * rate_ + 0.1 / seconds : rate_;
    step_cost_ = step_cost_ > 0 ? 0.8 * step_cost_ + 0.2 * seconds : seconds;
    ++steps_;
    if (!r.ok) unstable_ = r.message;
    recordWrench();
  }

  /// The world's live settings: dt, the first body's material, the solver.
  std::string settingsText() const {
    const Material& m = scene_->world->bodies().front()->model().material();
    const SolverSettings& s = scene_->world->settings().solver;
    char buf[200];
    std::snprintf(buf, sizeof buf, "DT %g S  E %g PA  NU %.2f  BETA %g S  %s%s", s.time_step,
                  m.youngs_modulus, m.poisson_ratio, m.stiffness_damping, toString(s.linear_solver),
                  s.linear_solver == LinearSolverKind::kCholmod
                      ? ""
                      : (std::string(" ") + toString(s.preconditioner)).c_str());
    return buf;
  }

  /// "world at step N, t = T s; DT ..." for the log and the exit summary.
  std::string worldText() const {
    char buf[96];
    std::snprintf(buf, sizeof buf, "world at step %d, t = %.6g s; ", scene_->world->stepCount(),
                  scene_->world->time());
    return buf + settingsText();
  }

  render::FrameData frame() {
    render::FrameData f = render::captureFrame(*scene_, rate_);
    f.notes.push_back(settingsText());
    if (!history_.times.empty()) f.plots.push_back(history_);
    f.notes.push_back(std::string(paused_ ? "PAUSED" : "RUNNING") + "  " + controlNote());
    if (!unstable_.empty()) {
      f.notes.push_back("STOPPED: " + unstable_.substr(0, 60));
    } else if (!paused_) {
      f.notes.push_back(options_.steps_per_frame > 0
                            ? std::to_string(options_.steps_per_frame) + " STEPS PER FRAME"
                            : realTimeNote(shown_factor_));
    }
    f.notes.push_back("KEYS SPACE N R F  T E P D C  M G U ARROWS PGUP PGDN");
    if (manual_ && hand() && !hand()->hand->grabbed()) {
      render::HandDrawData d;
      d.name = hand()->spec.name;
      d.frame = manual_frame_;
      d.plane_half_size = 0.1 * sceneSize();
      for (render::HandDrawData& existing : f.hands) {
        if (existing.name == d.name) existing = d;
      }
    }
    return f;
  }

  bool quit() const { return quit_; }
  bool takeReframe() {
    const bool r = reframe_;
    reframe_ = false;
    return r;
  }
  const Camera& camera() const { return camera_; }
  std::vector<std::string> hapticsDescription() const {
    return scene_->haptics ? scene_->haptics->describe() : std::vector<std::string>{};
  }
  int steps() const { return steps_; }
  bool stable() const { return unstable_.empty(); }
  const std::string& failure() const { return unstable_; }
  bool manual() const { return manual_; }
  /// The first hand follows a device (the scene's, or --device).
  bool deviceHand() const {
    return !scene_->hands.empty() && scene_->hands.front().spec.device.has_value();
  }
  /// One line per hand: where its goal (the device's or the script's frame) and its grabbed
  /// patch are (poseText).
  std::vector<std::string> handReport() const {
    std::vector<std::string> lines;
    for (const scene::SceneHand& h : scene_->hands) {
      std::string line = "hand '" + h.spec.name + "' (" +
                         (h.spec.device                             ? "device"
                          : manual_ && &h == &scene_->hands.front() ? "manual"
                                                                    : "scripted") +
                         "): goal " + poseText(h.hand->goal());
      if (h.hand->grabbed()) {
        line += ", patch " + poseText(h.hand->frame()) + ", " +
                std::to_string(h.hand->grabbedNodes().size()) + " nodes grabbed";
      } else {
        line += ", nothing grabbed";
      }
      lines.push_back(line);
    }
    return lines;
  }
  /// One line per tool with a device: its device's kind, where the device holds it (the goal)
  /// and where its body is (poseText), and a grasper's jaw gap.
  std::vector<std::string> toolReport() const {
    std::vector<std::string> lines;
    if (!scene_->haptics) return lines;
    for (const scene::SceneHaptics::ToolState& t : scene_->haptics->tools())
      lines.push_back(toolText(t));
    return lines;
  }
  int grabbedNodes() {
    return hand() && hand()->hand->grabbed() ? static_cast<int>(hand()->hand->grabbedNodes().size())
                                             : 0;
  }

 private:
  double sceneSize() const {
    Eigen::AlignedBox3d b;
    for (const auto& body : scene_->world->bodies()) {
      for (int i = 0; i < body->model().nodeCount(); ++i)
        b.extend(body->state().position(i));
    }
    return b.isEmpty() ? 1.0 : std::max(1e-3, b.diagonal().norm());
  }

  scene::SceneHand* hand() { return scene_->hands.empty() ? nullptr : &scene_->hands.front(); }

  // The manual input moves the tool with the manual device unless M took a hand.
  bool toolHasKeys() const { return tool_ && !manual_; }

  // Applies `change` to the world frame the manual input moves: the manual tool's, else the
  // hand taken with M (the first hand, taken now if needed).
  template <class Change>
  void moveManual(Change change) {
    if (toolHasKeys()) {
      Frame goal = tool_->goal();
      change(goal);
      tool_->moveTo(goal);
      return;
    }
    if (!manual_ && !toggleManual()) return;
    change(manual_frame_);
  }

  // G / U on the manual tool, logged with the moment and, for a grasper, the jaws' gap then.
  void holdToolButton(bool held) {
    tool_->holdButton(held);
    char when[64];
    std::snprintf(when, sizeof when, " at step %d, t = %.6g s", scene_->world->stepCount(),
                  scene_->world->time());
    std::string line =
        "viewer: tool '" + tool_->name() + "': button 1 " + (held ? "held" : "let go") + when;
    for (const scene::SceneHaptics::ToolState& t : scene_->haptics->tools()) {
      if (t.name == tool_->name() && t.jaw_gap) line += "; jaws " + gapText(*t.jaw_gap);
    }
    std::cout << line << std::endl;
  }

  static std::string gapText(double gap) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.6g m apart", gap);
    return buf;
  }

  // "tool 'probe' (manual): goal at ... , body at ...[, jaws ... m apart]"
  std::string toolText(const scene::SceneHaptics::ToolState& t) const {
    std::string line =
        "tool '" + t.name + "' (" + scene::toString(t.kind) + "): goal " + poseText(t.goal);
    for (const scene::SceneRigidBody& r : scene_->rigid_bodies) {
      if (r.name != t.name) continue;
      const btTransform& pose = r.body->getCenterOfMassTransform();
      Frame body;
      body.origin = toEigen(pose.getOrigin());
      body.rotation = toEigen(pose.getRotation());
      line += ", body " + poseText(body);
    }
    if (t.jaw_gap) line += ", jaws " + gapText(*t.jaw_gap);
    if (tool_ && tool_->name() == t.name) {  // what its device renders (device frame)
      const Wrench w = tool_->rendered();
      char buf[96];
      std::snprintf(buf, sizeof buf, ", renders (%.6g, %.6g, %.6g) N", w.force.x(), w.force.y(),
                    w.force.z());
      line += buf;
    }
    return line;
  }

  // The HUD's word on what the manual input moves.
  std::string controlNote() const {
    if (manual_)
      return tool_ ? "HAND: MANUAL (G GRAB, U RELEASE, M TOOL)"
                   : "HAND: MANUAL (G GRAB, U RELEASE)";
    if (tool_) return tool_->grasper() ? "TOOL: MANUAL (G CLOSE, U OPEN)" : "TOOL: MANUAL";
    return deviceHand() ? "HAND: DEVICE" : "HAND: SCRIPT (M MANUAL)";
  }

  // Returns whether the hand is under manual control now.
  bool toggleManual() {
    if (manual_) {
      manual_ = false;
      return false;
    }
    if (deviceHand()) {  // the device moves it: two masters would fight
      std::cerr << "viewer: hand '" << hand()->spec.name
                << "' follows its device: no manual control\n";
      return false;
    }
    if (scene_->hands.empty()) {  // a hand of our own on the first body
      scene::SceneHand h;
      h.spec.name = "mouse";
      h.spec.body = scene_->world->bodies().front()->name();
      h.spec.grab_at = std::numeric_limits<double>::infinity();
      FemBody& body = *scene_->world->bodies().front();
      h.hand = std::make_unique<Hand>(body, "mouse");
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      for (int i = 0; i < body.model().nodeCount(); ++i)
        centre += body.state().position(i);
      h.spec.initial.origin = centre / std::max(1, body.model().nodeCount());
      scene_->hands.push_back(std::move(h));
    }
    scene::SceneHand& h = *hand();
    h.scripted = false;  // from now on it stays where the keys leave it, even after M again
    manual_frame_ = h.hand->grabbed() ? h.hand->frame() : h.spec.frameAt(scene_->world->time());
    manual_ = true;
    return true;
  }

  void grab() {
    if (!manual_ && !toggleManual()) return;
    Result<int> n = hand()->hand->grab(manual_frame_, scene_->world->time());
    if (!n) std::cerr << "viewer: grab: " << n.error().message << "\n";
  }

  // Live edits: the running world takes them between two steps and goes on from its current
  // state (FemWorld::setSolverSettings, FemBody::setMaterial); the scene spec follows, so a
  // reset (R) restarts with them. A refused value leaves everything as it was.
  template <class Edit>
  void editSolver(Edit edit) {
    SolverSettings s = scene_->world->settings().solver;
    edit(s);
    if (Status ok = scene_->world->setSolverSettings(s); !ok) {
      std::cerr << "viewer: refused: " << ok.error().message << "\n";
      return;
    }
    const int threads = spec_.world.solver.threads;  // may differ from the world's (--threads)
    spec_.world.solver = s;
    spec_.world.solver.threads = threads;
    std::cout << "viewer: live edit, " << worldText() << std::endl;
  }

  template <class Edit>
  void editMaterial(Edit edit) {
    for (const auto& body : scene_->world->bodies()) {
      Material m = body->model().material();
      edit(m);
      if (Status ok = body->setMaterial(m); !ok) {
        std::cerr << "viewer: refused: " << ok.error().message << "\n";
        return;
      }
      for (scene::BodySpec& b : spec_.bodies) {
        if (b.name == body->name()) b.material = m;
      }
    }
    for (scene::SceneHand& h : scene_->hands)
      h.hand->updateSpeedLimit();  // a fraction of the new shear wave speed
    std::cout << "viewer: live edit, " << worldText() << std::endl;
  }

  // After each step, for the scrolling plot (the last kHistory steps): the wrench the manual
  // tool's device renders while the manual input moves the tool, else the first hand's.
  void recordWrench() {
    static constexpr size_t kHistory = 300;
    if (!toolHasKeys() && !hand()) return;
    const Wrench w = toolHasKeys() ? tool_->rendered() : hand()->hand->wrench();
    const std::string& name = toolHasKeys() ? tool_->name() : hand()->spec.name;
    if (history_.name != name) history_ = render::WrenchHistory{};  // one series at a time
    history_.name = name;
    history_.times.push_back(scene_->world->time());
    history_.forces.push_back(w.force);
    history_.torques.push_back(w.torque);
    if (history_.times.size() > kHistory) {
      history_.times.erase(history_.times.begin());
      history_.forces.erase(history_.forces.begin());
      history_.torques.erase(history_.torques.begin());
    }
  }

  void reset() {
    if (Status s = rebuild(); !s) std::cerr << "viewer: reset: " << s.error().message << "\n";
  }

  ViewerOptions options_;
  scene::SceneSpec spec_;
  std::unique_ptr<scene::BuiltScene> scene_;
  std::optional<ManualToolControl> tool_;  // the tool with a manual device (rebuild)
  Camera camera_;
  Frame manual_frame_;
  bool manual_ = false, paused_ = false, single_step_ = false, quit_ = false, reframe_ = false;
  double rate_ = 0;
  double step_cost_ = 0;     // s of wall time per step, smoothed (pacing)
  double lag_ = 0;           // s of simulated time owed to the wall clock (pacing)
  double shown_factor_ = 1;  // real-time factor on the HUD, smoothed
  int steps_ = 0;
  std::string unstable_;
  render::WrenchHistory history_;
};

// The scene file with --device / --haptics applied, and the --script events.
struct ViewerInput {
  scene::SceneSpec spec;
  std::vector<InputEvent> script;
};

Result<ViewerInput> loadInput(const ViewerOptions& options) {
  Result<scene::SceneSpec> spec = scene::loadScene(options.scene);
  if (!spec) return spec.error();
  ViewerInput input;
  if (!options.script.empty()) {
    auto read = readScript(options.script);
    if (!read) return read.error();
    input.script = std::move(read).value();
  }
  if (Status applied = scene::applyDeviceOverrides(spec.value(), options.devices); !applied)
    return applied.error();
  for (const std::string& w : scene::remoteDeviceWarnings(spec.value()))
    std::cerr << "warning: " << w << "\n";  // as `torsion run` says it
  input.spec = std::move(spec).value();
  return input;
}

// The framebuffer as drawn into a PNG.
void writeScreenshot(const ViewerWindow& window, int width, int height, const std::string& path) {
  if (Status w = render::writePng(window.readPixels(width, height), path); !w)
    std::cerr << "error: " << w.error().message << "\n";
}

// Frames until the window closes, Q, or --frames: script events due, reframe, one advance of the
// simulation, draw, and on the last frame the screenshot. Returns the frames shown.
int showFrames(Viewer& viewer, ViewerWindow& window, const std::vector<InputEvent>& script,
               const ViewerOptions& options) {
  render::Renderer renderer(window.gl());
  int width = 0, height = 0;
  window.framebufferSize(width, height);
  viewer.frameAll(width, height);
  size_t next_event = 0;
  int frames = 0;
  auto last_frame = std::chrono::steady_clock::now();
  while (!window.closeRequested() && !viewer.quit()) {
    ViewerWindow::pollEvents();
    while (next_event < script.size() && script[next_event].frame <= frames)
      viewer.apply(script[next_event++], height);
    window.framebufferSize(width, height);
    if (viewer.takeReframe()) viewer.frameAll(width, height);
    const auto now = std::chrono::steady_clock::now();
    viewer.advanceFrame(std::chrono::duration<double>(now - last_frame).count());
    last_frame = now;
    render::RenderOptions ro;
    renderer.draw(viewer.frame(), viewer.camera(), width, height, ro);
    ++frames;
    const bool last = options.frames > 0 && frames >= options.frames;
    if ((last || viewer.quit()) && !options.screenshot.empty())
      writeScreenshot(window, width, height, options.screenshot);
    window.swapBuffers();
    if (last) break;
  }
  return frames;
}

// On stdout at exit: frames, steps, the hand's mode and hold, stability, the live settings,
// each hand's goal and patch, and each tool's goal and body.
void printExitReport(Viewer& viewer, int frames) {
  std::cout << "viewer: " << frames << " frames, " << viewer.steps() << " steps, hand "
            << (viewer.manual()       ? "manual"
                : viewer.deviceHand() ? "device"
                                      : "scripted")
            << ", " << viewer.grabbedNodes() << " nodes grabbed, "
            << (viewer.stable() ? "stable" : "unstable: " + viewer.failure()) << "\n";
  std::cout << "viewer: " << viewer.worldText() << "\n";
  for (const std::string& line : viewer.handReport())
    std::cout << "viewer: " << line << "\n";
  for (const std::string& line : viewer.toolReport())
    std::cout << "viewer: " << line << "\n";
}

}  // namespace

// The viewer as its stages: the input, the scene built (devices opened), the window, the frames,
// the exit report.
int runViewer(const ViewerOptions& options) {
  Result<ViewerInput> input = loadInput(options);
  if (!input) {
    std::cerr << "error: " << input.error().message << "\n";
    return 1;
  }
  Viewer viewer(options, std::move(input.value().spec));
  // Opens the devices too: a SpaceMouse without its daemon stops here, before any window.
  if (Status built = viewer.rebuild(); !built) {
    std::cerr << "error: " << built.error().message << "\n";
    return 1;
  }
  for (const std::string& line : viewer.hapticsDescription())
    std::cerr << line << "\n";
  int frames = 0;
  {
    WindowSettings settings;
    settings.width = options.width;
    settings.height = options.height;
    settings.title = "torsion view: " + options.scene;
    settings.vsync = options.frames <= 0;
    Result<std::unique_ptr<ViewerWindow>> window = ViewerWindow::open(settings);
    if (!window) {
      std::cerr << "error: " << window.error().message << "\n";
      return 1;
    }
    window.value()->connect(viewer);
    frames = showFrames(viewer, *window.value(), input.value().script, options);
  }  // the window closes before the report
  printExitReport(viewer, frames);
  return viewer.stable() ? 0 : 3;
}

}  // namespace torsion::viewer
