// The 2D overlay of a picture: the HUD panel (top left: scene, time, one line and one row of bars
// per wrench), the viewer's notes (bottom left), the stress legend (right) and the scrolling
// wrench plot (bottom right). Kept compact so the scene, not the numbers, fills the picture.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "font.h"
#include "renderer.h"

namespace torsion::render {

namespace {

const Eigen::Vector3d kText(0.08, 0.1, 0.16);
const Eigen::Vector3d kAxisColour[3] = {{0.85, 0.1, 0.1}, {0.1, 0.6, 0.15}, {0.1, 0.1, 0.9}};

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", std::abs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

std::string magnitude(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2e", v < 1e-12 ? 0.0 : v);
  return buf;
}

double textWidth(const std::string& s, double scale) {
  return (kGlyphWidth + 1) * scale * static_cast<double>(s.size());
}

// Sizes of the HUD panel, in units of the font pixel, shared by the drawing and the camera fit.
struct HudLayout {
  static constexpr double kMargin = 6, kLine = kGlyphHeight + 4, kBar = 3, kBarWidth = 22,
                          kBarGap = 2, kGroupGap = 6;
  std::string status;
  std::vector<std::string> wrench_lines;

  explicit HudLayout(const FrameData& frame) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "  T %.2f S  STEP %d", frame.time, frame.step);
    status = frame.title + buf;
    if (frame.steps_per_second > 0) {
      std::snprintf(buf, sizeof buf, "  %.0f STEPS/S", frame.steps_per_second);
      status += buf;
    }
    size_t name_width = 0;
    for (const WrenchReadout& w : frame.wrenches)
      name_width = std::max(name_width, w.name.size());
    for (const WrenchReadout& w : frame.wrenches) {
      wrench_lines.push_back(w.name + std::string(name_width - w.name.size(), ' ') + " |F| " +
                             magnitude(w.force.norm()) + " N  |T| " + magnitude(w.torque.norm()) +
                             " NM");
    }
  }
  /// Panel height in font pixels.
  double height() const {
    return kLine + static_cast<double>(wrench_lines.size()) * (kLine + kBar + 3) + 2;
  }
  double barsWidth() const { return 6 * kBarWidth + 4 * kBarGap + kGroupGap; }
};

}  // namespace

double textScale(int height, const RenderOptions& options) {
  const double picture_pixels = height / options.pixel_scale / 480.0;
  const double step = options.pixel_scale >= 2 ? 0.5 : 1.0;  // whole drawn pixels
  return std::max(1.0, std::round(picture_pixels / step) * step) * options.pixel_scale;
}

int sceneViewportWidth(int width, int height, const RenderOptions& options) {
  if (!options.legend || !options.stress) return width;
  return std::max(1, width - static_cast<int>(std::lround(62 * textScale(height, options))));
}

double hudHeightFraction(const FrameData& frame, int height, const RenderOptions& options) {
  if (!options.hud || height <= 0) return 0;
  const double ts = textScale(height, options);
  return std::min(0.5, (HudLayout(frame).height() + 2 * HudLayout::kMargin) * ts / height);
}

void Renderer::drawOverlay(const FrameData& frame, int width, int height,
                           const RenderOptions& options) {
  const GlApi& gl = gl_;
  gl.Disable(GL_DEPTH_TEST);
  gl.Disable(GL_LIGHTING);
  gl.Enable(GL_BLEND);
  gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  gl.MatrixMode(GL_PROJECTION);
  gl.LoadIdentity();
  gl.Ortho(0, width, height, 0, -1, 1);  // pixels, y down
  gl.MatrixMode(GL_MODELVIEW);
  gl.LoadIdentity();
  const double ts = textScale(height, options);
  if (options.hud) {
    drawHud(frame, ts);
    drawNotes(frame, height, ts);
    if (!frame.plots.empty()) {
      // Wide enough for its titles ("<name> T, NM +-1.23e-04": 8 characters for the magnitude).
      const double plot_width =
          std::max(120 * ts, textWidth(frame.plots.front().name + " T, NM +-0.00e+00", ts));
      const double plot_height = 2 * (HudLayout::kLine + 26 + 4) * ts;
      drawWrenchPlot(frame.plots.front(), width - HudLayout::kMargin * ts - plot_width,
                     height - HudLayout::kMargin * ts - plot_height, plot_width, ts);
    }
  }
  if (options.legend && options.stress && !frame.bodies.empty())
    drawLegend(frame, width, height, ts);
  gl.Disable(GL_BLEND);
  gl.Enable(GL_DEPTH_TEST);
}

void Renderer::drawBar(double x, double y, double width, double height, double value, double scale,
                       const Eigen::Vector3d& colour) {
  const double mid = x + width / 2;
  gl_.Begin(GL_QUADS);
  gl_.Color4d(0.6, 0.62, 0.68, 0.5);
  quad2d(x, y, x + width, y + height);
  gl_.Color4d(colour.x(), colour.y(), colour.z(), 1);
  quad2d(mid, y, mid + 0.5 * width * std::clamp(value / scale, -1.0, 1.0), y + height);
  gl_.End();
}

void Renderer::drawHud(const FrameData& frame, double ts) {
  const HudLayout layout(frame);
  const double m = HudLayout::kMargin * ts, line = HudLayout::kLine * ts;
  double panel_width = std::max(textWidth(layout.status, ts),
                                frame.wrenches.empty() ? 0.0 : layout.barsWidth() * ts);
  for (const std::string& l : layout.wrench_lines)
    panel_width = std::max(panel_width, textWidth(l, ts));
  gl_.Color4d(1, 1, 1, 0.6);
  gl_.Begin(GL_QUADS);
  quad2d(m - 3 * ts, m - 3 * ts, m + panel_width + 3 * ts, m + layout.height() * ts);
  gl_.End();
  gl_.Color4d(kText.x(), kText.y(), kText.z(), 1);
  drawText(m, m, ts, layout.status);
  double top = m + line;
  // Bars of a readout are scaled to its largest component, but never below 1e-3 of the largest
  // force (torque) on screen, so round-off shows as no bar.
  double force_floor = 1e-12, torque_floor = 1e-12;
  for (const WrenchReadout& w : frame.wrenches) {
    force_floor = std::max(force_floor, 1e-3 * w.force.cwiseAbs().maxCoeff());
    torque_floor = std::max(torque_floor, 1e-3 * w.torque.cwiseAbs().maxCoeff());
  }
  for (size_t k = 0; k < frame.wrenches.size(); ++k) {
    const WrenchReadout& w = frame.wrenches[k];
    gl_.Color4d(kText.x(), kText.y(), kText.z(), 1);
    drawText(m, top, ts, layout.wrench_lines[k]);
    top += line;
    // Force x, y, z, then torque x, y, z, each signed about its centre.
    double x = m;
    for (int row = 0; row < 2; ++row) {
      const Eigen::Vector3d& v = row == 0 ? w.force : w.torque;
      const double scale = std::max(v.cwiseAbs().maxCoeff(), row == 0 ? force_floor : torque_floor);
      for (int a = 0; a < 3; ++a) {
        drawBar(x, top, HudLayout::kBarWidth * ts, HudLayout::kBar * ts, v[a], scale,
                kAxisColour[a]);
        x += (HudLayout::kBarWidth + HudLayout::kBarGap) * ts;
      }
      x += (HudLayout::kGroupGap - HudLayout::kBarGap) * ts;
    }
    top += (HudLayout::kBar + 3) * ts;
  }
}

void Renderer::drawNotes(const FrameData& frame, int height, double ts) {
  if (frame.notes.empty()) return;
  const double m = HudLayout::kMargin * ts, line = HudLayout::kLine * ts;
  double y = height - m - line * static_cast<double>(frame.notes.size());
  double w = 0;
  for (const std::string& l : frame.notes)
    w = std::max(w, textWidth(l, ts));
  gl_.Color4d(1, 1, 1, 0.6);
  gl_.Begin(GL_QUADS);
  quad2d(m - 3 * ts, y - 3 * ts, m + w + 3 * ts, height - m + ts);
  gl_.End();
  gl_.Color4d(kText.x(), kText.y(), kText.z(), 1);
  for (const std::string& l : frame.notes) {
    drawText(m, y, ts, l);
    y += line;
  }
}

void Renderer::drawLegend(const FrameData& frame, int width, int height, double ts) {
  const double line = HudLayout::kLine * ts, m = HudLayout::kMargin * ts;
  const double bar_w = 10 * ts, bar_h = 0.32 * height;
  const double x0 = width - m - bar_w - 40 * ts, y0 = 0.5 * (height - bar_h);
  gl_.Color4d(1, 1, 1, 0.6);
  gl_.Begin(GL_QUADS);
  quad2d(x0 - 4 * ts, y0 - 3 * line, width - m + 2 * ts, y0 + bar_h + 2.2 * line);
  const int segments = 32;
  for (int i = 0; i < segments; ++i) {
    const double s0 = double(i) / segments, s1 = double(i + 1) / segments;
    const Eigen::Vector3d c0 = stressColour(s0), c1 = stressColour(s1);
    const double ya = y0 + bar_h * (1 - s0), yb = y0 + bar_h * (1 - s1);
    gl_.Color4d(c0.x(), c0.y(), c0.z(), 1);
    gl_.Vertex2d(x0, ya);
    gl_.Vertex2d(x0 + bar_w, ya);
    gl_.Color4d(c1.x(), c1.y(), c1.z(), 1);
    gl_.Vertex2d(x0 + bar_w, yb);
    gl_.Vertex2d(x0, yb);
  }
  gl_.End();
  gl_.Color4d(kText.x(), kText.y(), kText.z(), 1);
  // Labels in Pa, kPa or MPa so that they stay short.
  double unit = 1;
  const char* unit_name = "PA";
  if (frame.stress_max >= 1e6) {
    unit = 1e6;
    unit_name = "MPA";
  } else if (frame.stress_max >= 1e3) {
    unit = 1e3;
    unit_name = "KPA";
  }
  drawText(x0 - 2 * ts, y0 - 2.6 * line, ts, "MISES");
  drawText(x0 - 2 * ts, y0 - 1.6 * line, ts, unit_name);
  for (int k = 0; k <= 4; k += 2) {
    const double s = k / 4.0, y = y0 + bar_h * (1 - s);
    gl_.Begin(GL_QUADS);
    quad2d(x0 + bar_w, y - 0.5 * ts, x0 + bar_w + 3 * ts, y + 0.5 * ts);
    gl_.End();
    drawText(x0 + bar_w + 5 * ts, y - 3.5 * ts, ts, number(s * frame.stress_max / unit));
  }
  // The grabbed-node swatch under the bar.
  const double swatch_y = y0 + bar_h + 0.8 * line;
  gl_.Color4d(kGrabbedOrange.x(), kGrabbedOrange.y(), kGrabbedOrange.z(), 1);
  gl_.Begin(GL_QUADS);
  quad2d(x0, swatch_y, x0 + bar_w, swatch_y + 7 * ts);
  gl_.End();
  gl_.Color4d(kText.x(), kText.y(), kText.z(), 1);
  drawText(x0 + bar_w + 5 * ts, swatch_y, ts, "GRAB");
}

void Renderer::drawWrenchPlot(const WrenchHistory& history, double x, double y, double width,
                              double ts) {
  const double line = HudLayout::kLine * ts, graph_h = 26 * ts, gap = 4 * ts;
  const double total = 2 * (line + graph_h + gap);
  gl_.Color4d(1, 1, 1, 0.6);
  gl_.Begin(GL_QUADS);
  quad2d(x - 3 * ts, y - 3 * ts, x + width + 3 * ts, y + total);
  gl_.End();
  const double t_end = history.times.empty() ? 0 : history.times.back();
  const double t_begin = history.times.empty() ? 0 : history.times.front();
  const double span = std::max(1e-9, t_end - t_begin);
  for (int row = 0; row < 2; ++row) {
    const std::vector<Eigen::Vector3d>& values = row == 0 ? history.forces : history.torques;
    double peak = 0;
    for (const Eigen::Vector3d& v : values)
      peak = std::max(peak, v.cwiseAbs().maxCoeff());
    const double scale = peak > 0 ? peak : 1;
    gl_.Color4d(kText.x(), kText.y(), kText.z(), 1);
    drawText(x, y, ts, history.name + (row == 0 ? " F, N " : " T, NM ") + "+-" + magnitude(peak));
    const double top = y + line, mid = top + graph_h / 2;
    gl_.Color4d(0.6, 0.62, 0.68, 0.35);
    gl_.Begin(GL_QUADS);
    quad2d(x, top, x + width, top + graph_h);
    gl_.End();
    gl_.Color4d(0.3, 0.32, 0.4, 0.8);
    gl_.LineWidth(static_cast<GLfloat>(ts / 2));
    gl_.Begin(GL_LINES);
    gl_.Vertex2d(x, mid);
    gl_.Vertex2d(x + width, mid);
    gl_.End();
    gl_.LineWidth(static_cast<GLfloat>(ts));
    for (int a = 0; a < 3; ++a) {
      gl_.Color4d(kAxisColour[a].x(), kAxisColour[a].y(), kAxisColour[a].z(), 1);
      gl_.Begin(GL_LINE_STRIP);
      for (size_t k = 0; k < values.size() && k < history.times.size(); ++k) {
        const double px = x + width * (history.times[k] - t_begin) / span;
        gl_.Vertex2d(px, mid - 0.5 * graph_h * values[k][a] / scale);
      }
      gl_.End();
    }
    y = top + graph_h + gap;
  }
}

}  // namespace torsion::render
