#include "renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "font.h"

namespace torsion::render {

namespace {

const Eigen::Vector3d kPlainBody(0.72, 0.74, 0.78);

}  // namespace

void Renderer::draw(const FrameData& frame, const Camera& camera, int width, int height,
                    const RenderOptions& options) {
  const GlApi& gl = gl_;
  const int scene_width = sceneViewportWidth(width, height, options);
  eye_ = camera.eye();
  gl.Viewport(0, 0, width, height);
  gl.ClearColor(0.95f, 0.95f, 0.96f, 1.0f);
  gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  drawBackground();

  gl.Viewport(0, 0, scene_width, height);
  gl.MatrixMode(GL_PROJECTION);
  const Eigen::Matrix4d projection =
      camera.projection(static_cast<double>(scene_width) / std::max(1, height));
  gl.LoadMatrixd(projection.data());
  gl.MatrixMode(GL_MODELVIEW);
  gl.LoadIdentity();
  // A head light, up and to the left of the viewer, set in eye coordinates.
  const GLfloat light_dir[4] = {-0.35f, 0.55f, 0.76f, 0.0f};
  const GLfloat ambient[4] = {0.32f, 0.32f, 0.32f, 1.0f};
  const GLfloat diffuse[4] = {0.72f, 0.72f, 0.72f, 1.0f};
  const GLfloat none[4] = {0, 0, 0, 1};
  gl.Lightfv(GL_LIGHT0, GL_POSITION, light_dir);
  gl.Lightfv(GL_LIGHT0, GL_AMBIENT, none);
  gl.Lightfv(GL_LIGHT0, GL_DIFFUSE, diffuse);
  gl.Lightfv(GL_LIGHT0, GL_SPECULAR, none);
  gl.LightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
  // One-sided on purpose: a surface whose normals point inward shows dark.
  gl.LightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_FALSE);
  gl.Enable(GL_LIGHT0);
  gl.ColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
  gl.Materialfv(GL_FRONT_AND_BACK, GL_SPECULAR, none);
  gl.Enable(GL_NORMALIZE);
  gl.ShadeModel(GL_SMOOTH);
  gl.LoadMatrixd(camera.view().data());

  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LEQUAL);
  drawGround(frame, camera.up);
  drawBodies(frame, options);
  drawRigids(frame);
  drawHands(frame, options);
  gl.Viewport(0, 0, width, height);
  drawOverlay(frame, width, height, options);
  gl.Finish();
}

void Renderer::drawBackground() {
  const GlApi& gl = gl_;
  gl.Disable(GL_DEPTH_TEST);
  gl.Disable(GL_LIGHTING);
  gl.MatrixMode(GL_PROJECTION);
  gl.LoadIdentity();
  gl.MatrixMode(GL_MODELVIEW);
  gl.LoadIdentity();
  gl.Begin(GL_QUADS);
  gl.Color4d(0.80, 0.84, 0.90, 1);
  gl.Vertex2d(-1, -1);
  gl.Vertex2d(1, -1);
  gl.Color4d(0.97, 0.97, 0.98, 1);
  gl.Vertex2d(1, 1);
  gl.Vertex2d(-1, 1);
  gl.End();
}

void Renderer::drawGround(const FrameData& frame, const Eigen::Vector3d& up) {
  const GlApi& gl = gl_;
  const double size = std::max(1e-3, frame.bounds.diagonal().norm());
  const Eigen::Vector3d centre = frame.bounds.center();
  bool has_plane = false;
  for (const RigidDrawData& r : frame.rigids) {
    if (r.shape != RigidDrawData::Shape::kPlane) continue;
    has_plane = true;
    // A checkered square around the scene's foot on the plane.
    const Eigen::Vector3d n = r.normal.normalized();
    const Eigen::Vector3d foot = centre - (n.dot(centre) - r.offset) * n;
    const Eigen::Vector3d a = n.unitOrthogonal(), b = n.cross(a);
    const int cells = 16;
    const double half = 1.5 * size, cell = 2 * half / cells;
    gl.Enable(GL_LIGHTING);
    gl.Enable(GL_COLOR_MATERIAL);
    gl.Enable(GL_POLYGON_OFFSET_FILL);
    gl.PolygonOffset(1, 1);
    gl.Begin(GL_QUADS);
    gl.Normal3d(n.x(), n.y(), n.z());
    for (int i = 0; i < cells; ++i) {
      for (int j = 0; j < cells; ++j) {
        const double shade = ((i + j) % 2) ? 0.78 : 0.86;
        gl.Color4d(shade, shade, shade * 0.97, 1);
        const Eigen::Vector3d o = foot + (-half + i * cell) * a + (-half + j * cell) * b;
        for (const Eigen::Vector3d& p :
             {o, Eigen::Vector3d(o + cell * a), Eigen::Vector3d(o + cell * a + cell * b),
              Eigen::Vector3d(o + cell * b)})
          gl.Vertex3d(p.x(), p.y(), p.z());
      }
    }
    gl.End();
    gl.Disable(GL_POLYGON_OFFSET_FILL);
  }
  if (has_plane) return;
  // No ground in the scene: a faint grid below it, for orientation.
  gl.Disable(GL_LIGHTING);
  gl.Enable(GL_BLEND);
  gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  double low = 0;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? frame.bounds.max().x() : frame.bounds.min().x(),
                                 (c & 2) ? frame.bounds.max().y() : frame.bounds.min().y(),
                                 (c & 4) ? frame.bounds.max().z() : frame.bounds.min().z());
    low = c == 0 ? up.dot(corner) : std::min(low, up.dot(corner));
  }
  const Eigen::Vector3d foot = centre + (low - 0.05 * size - up.dot(centre)) * up;
  const Eigen::Vector3d a = up.unitOrthogonal(), b = up.cross(a);
  const int lines = 12;
  const double half = 0.9 * size, cell = 2 * half / lines;
  gl.Color4d(0.3, 0.35, 0.45, 0.35);
  gl.LineWidth(1);
  gl.Begin(GL_LINES);
  for (int i = 0; i <= lines; ++i) {
    for (const auto& [u, v] : {std::pair(a, b), std::pair(b, a)}) {
      const Eigen::Vector3d p = foot + (-half + i * cell) * u - half * v;
      const Eigen::Vector3d q = p + 2 * half * v;
      gl.Vertex3d(p.x(), p.y(), p.z());
      gl.Vertex3d(q.x(), q.y(), q.z());
    }
  }
  gl.End();
  gl.Disable(GL_BLEND);
}

void Renderer::drawBodies(const FrameData& frame, const RenderOptions& options) {
  const GlApi& gl = gl_;
  for (const BodyDrawData& body : frame.bodies) {
    if (body.triangles.empty()) continue;
    const size_t n = body.positions.size();
    colours_.assign(3 * n, 0.0f);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d c =
          options.stress && i < body.stress.size()
              ? stressColour(static_cast<double>(body.stress[i]) / frame.stress_max)
              : kPlainBody;
      for (size_t k = 0; k < 3; ++k)
        colours_[3 * i + k] = static_cast<float>(c[static_cast<Eigen::Index>(k)]);
    }
    for (int g : body.grabbed_nodes) {
      for (size_t k = 0; k < 3; ++k)
        colours_[3 * static_cast<size_t>(g) + k] =
            static_cast<float>(kGrabbedOrange[static_cast<Eigen::Index>(k)]);
    }
    const auto* indices = reinterpret_cast<const GLuint*>(body.triangles.data());
    const auto count = static_cast<GLsizei>(3 * body.triangles.size());
    gl.EnableClientState(GL_VERTEX_ARRAY);
    gl.VertexPointer(3, GL_FLOAT, sizeof(Eigen::Vector3f), body.positions.data());
    gl.EnableClientState(GL_NORMAL_ARRAY);
    gl.NormalPointer(GL_FLOAT, sizeof(Eigen::Vector3f), body.normals.data());
    gl.EnableClientState(GL_COLOR_ARRAY);
    gl.ColorPointer(3, GL_FLOAT, 0, colours_.data());
    gl.Enable(GL_LIGHTING);
    gl.Enable(GL_COLOR_MATERIAL);
    gl.Enable(GL_POLYGON_OFFSET_FILL);  // the mesh lines and node points sit in front
    gl.PolygonOffset(1, 1);
    gl.DrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, indices);
    gl.Disable(GL_POLYGON_OFFSET_FILL);
    gl.DisableClientState(GL_COLOR_ARRAY);
    gl.DisableClientState(GL_NORMAL_ARRAY);
    gl.Disable(GL_LIGHTING);
    if (options.mesh_lines) {
      gl.Enable(GL_BLEND);
      gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
      gl.DepthMask(GL_FALSE);
      gl.Color4d(0.05, 0.07, 0.12, 0.28);
      gl.LineWidth(static_cast<GLfloat>(options.pixel_scale));
      gl.PolygonMode(GL_FRONT_AND_BACK, GL_LINE);
      gl.DrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, indices);
      gl.PolygonMode(GL_FRONT_AND_BACK, GL_FILL);
      gl.DepthMask(GL_TRUE);
      gl.Disable(GL_BLEND);
    }
    gl.DisableClientState(GL_VERTEX_ARRAY);
    drawStripes(body, options);
    if (!body.grabbed_nodes.empty()) {
      gl.PointSize(static_cast<GLfloat>(4 * options.pixel_scale));
      gl.Color4d(kGrabbedOrange.x(), kGrabbedOrange.y(), kGrabbedOrange.z(), 1);
      gl.Begin(GL_POINTS);
      for (int g : body.grabbed_nodes) {
        const Eigen::Vector3f& p = body.positions[static_cast<size_t>(g)];
        gl.Vertex3d(static_cast<double>(p.x()), static_cast<double>(p.y()),
                    static_cast<double>(p.z()));
      }
      gl.End();
    }
  }
}

void Renderer::drawHands(const FrameData& frame, const RenderOptions& options) {
  const GlApi& gl = gl_;
  gl.Disable(GL_LIGHTING);
  for (const HandDrawData& h : frame.hands) {
    const Eigen::Matrix3d R = h.frame.rotation.toRotationMatrix();
    const Eigen::Vector3d o = h.frame.origin;
    const double s = h.plane_half_size;
    // The plane: a translucent square spanned by i and j, and its outline.
    gl.Enable(GL_BLEND);
    gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    gl.DepthMask(GL_FALSE);
    gl.Color4d(1.0, 0.78, 0.25, h.holding ? 0.30 : 0.18);
    const Eigen::Vector3d corners[4] = {
        o + s * (-R.col(0) - R.col(1)), o + s * (R.col(0) - R.col(1)),
        o + s * (R.col(0) + R.col(1)), o + s * (-R.col(0) + R.col(1))};
    gl.Begin(GL_QUADS);
    for (const Eigen::Vector3d& p : corners)
      gl.Vertex3d(p.x(), p.y(), p.z());
    gl.End();
    gl.DepthMask(GL_TRUE);
    gl.Color4d(0.75, 0.5, 0.05, 0.9);
    gl.LineWidth(static_cast<GLfloat>(1.5 * options.pixel_scale));
    gl.Begin(GL_LINE_LOOP);
    for (const Eigen::Vector3d& p : corners)
      gl.Vertex3d(p.x(), p.y(), p.z());
    gl.End();
    gl.Disable(GL_BLEND);
    // The axes i, j, k, drawn through the body (depth test off) so the frame is always seen.
    gl.Disable(GL_DEPTH_TEST);
    gl.LineWidth(static_cast<GLfloat>(3 * options.pixel_scale));
    gl.Begin(GL_LINES);
    const double length = 0.8 * s;
    for (int a = 0; a < 3; ++a) {
      gl.Color4d(a == 0 ? 0.9 : 0.1, a == 1 ? 0.75 : 0.15, a == 2 ? 0.95 : 0.1, 1);
      const Eigen::Vector3d tip = o + length * R.col(a);
      gl.Vertex3d(o.x(), o.y(), o.z());
      gl.Vertex3d(tip.x(), tip.y(), tip.z());
    }
    gl.End();
    gl.Enable(GL_DEPTH_TEST);
  }
}

void Renderer::quad2d(double x0, double y0, double x1, double y1) {
  gl_.Vertex2d(x0, y0);
  gl_.Vertex2d(x1, y0);
  gl_.Vertex2d(x1, y1);
  gl_.Vertex2d(x0, y1);
}

double Renderer::drawText(double x, double y, double scale, const std::string& text) {
  gl_.Begin(GL_QUADS);
  double pen = x;
  for (char c : text) {
    const auto& rows = glyph(c);
    for (int r = 0; r < kGlyphHeight; ++r) {
      for (int col = 0; col < kGlyphWidth; ++col) {
        if (rows[static_cast<size_t>(r)] & (0x10 >> col)) {
          quad2d(pen + col * scale, y + r * scale, pen + (col + 1) * scale, y + (r + 1) * scale);
        }
      }
    }
    pen += (kGlyphWidth + 1) * scale;
  }
  gl_.End();
  return pen - x;
}

void Renderer::drawStripes(const BodyDrawData& body, const RenderOptions& options) {
  // Without the depth test (the chords between nodes would dip under the bumpy surface and show
  // dashed), but only segments whose both ends face the eye: the front of the body.
  auto facing = [&](int i) {
    const Eigen::Vector3f& p = body.positions[static_cast<size_t>(i)];
    return body.normals[static_cast<size_t>(i)].cast<double>().dot(eye_ - p.cast<double>()) > 0;
  };
  gl_.Disable(GL_DEPTH_TEST);
  gl_.LineWidth(static_cast<GLfloat>(1.5 * options.pixel_scale));
  gl_.Color4d(0.97, 0.97, 0.99, 1);
  gl_.Begin(GL_LINES);
  for (const std::vector<int>& stripe : body.stripes) {
    for (size_t k = 1; k < stripe.size(); ++k) {
      if (!facing(stripe[k - 1]) || !facing(stripe[k])) continue;
      for (int i : {stripe[k - 1], stripe[k]}) {
        const Eigen::Vector3f& p = body.positions[static_cast<size_t>(i)];
        gl_.Vertex3d(static_cast<double>(p.x()), static_cast<double>(p.y()),
                     static_cast<double>(p.z()));
      }
    }
  }
  gl_.End();
  gl_.Enable(GL_DEPTH_TEST);
}

}  // namespace torsion::render
