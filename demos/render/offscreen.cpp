#include "offscreen.h"

#include <GL/osmesa.h>
#include <dlfcn.h>

#include <algorithm>

namespace torsion::render {

// The few OSMesa entry points, looked up in a privately opened libOSMesa.
struct OffscreenRenderer::OsMesa {
  void* library = nullptr;
  decltype(&::OSMesaCreateContextExt) create_context = nullptr;
  decltype(&::OSMesaMakeCurrent) make_current = nullptr;
  decltype(&::OSMesaDestroyContext) destroy_context = nullptr;
  decltype(&::OSMesaGetProcAddress) get_proc_address = nullptr;
  OSMesaContext context = nullptr;

  ~OsMesa() {
    if (context) destroy_context(context);
    if (library) dlclose(library);
  }
};

namespace {

// GlProcLoader is a plain function pointer: the loader reaches the library through this.
OffscreenRenderer::OsMesa* g_loading = nullptr;

}  // namespace

Result<std::unique_ptr<OffscreenRenderer>> OffscreenRenderer::create(int width, int height,
                                                                     int supersample) {
  if (width < 16 || height < 16 || width > 8192 || height > 8192)
    return Error{"picture size " + std::to_string(width) + "x" + std::to_string(height) +
                 " is outside 16..8192"};
  std::unique_ptr<OffscreenRenderer> r(new OffscreenRenderer);
  r->width_ = width;
  r->height_ = height;
  r->supersample_ = std::max(1, supersample);
  r->osmesa_ = std::make_unique<OsMesa>();
  OsMesa& m = *r->osmesa_;
  for (const char* name : {"libOSMesa.so.8", "libOSMesa.so"}) {
    m.library = dlopen(name, RTLD_NOW | RTLD_LOCAL);
    if (m.library) break;
  }
  if (!m.library)
    return Error{"headless rendering needs libOSMesa (Debian: libosmesa6): " +
                 std::string(dlerror())};
  m.create_context =
      reinterpret_cast<decltype(m.create_context)>(dlsym(m.library, "OSMesaCreateContextExt"));
  m.make_current =
      reinterpret_cast<decltype(m.make_current)>(dlsym(m.library, "OSMesaMakeCurrent"));
  m.destroy_context =
      reinterpret_cast<decltype(m.destroy_context)>(dlsym(m.library, "OSMesaDestroyContext"));
  m.get_proc_address =
      reinterpret_cast<decltype(m.get_proc_address)>(dlsym(m.library, "OSMesaGetProcAddress"));
  if (!m.create_context || !m.make_current || !m.destroy_context || !m.get_proc_address)
    return Error{"libOSMesa lacks the OSMesa entry points"};
  m.context = m.create_context(OSMESA_RGBA, 24, 0, 0, nullptr);
  if (!m.context) return Error{"OSMesa could not create a context"};
  const int w = width * r->supersample_, h = height * r->supersample_;
  r->buffer_.resize(static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
  if (!m.make_current(m.context, r->buffer_.data(), GL_UNSIGNED_BYTE, w, h))
    return Error{"OSMesa could not make its context current at " + std::to_string(w) + "x" +
                 std::to_string(h)};
  g_loading = &m;
  const std::string missing = loadGlApi(r->gl_, [](const char* name) -> void* {
    void* p = reinterpret_cast<void*>(g_loading->get_proc_address(name));
    return p ? p : dlsym(g_loading->library, name);
  });
  g_loading = nullptr;
  if (!missing.empty()) return Error{"OSMesa lacks " + missing};
  r->renderer_ = std::make_unique<Renderer>(r->gl_);
  return r;
}

OffscreenRenderer::~OffscreenRenderer() = default;

Image OffscreenRenderer::render(const FrameData& frame, const Camera& camera,
                                RenderOptions options) {
  const int w = width_ * supersample_, h = height_ * supersample_;
  osmesa_->make_current(osmesa_->context, buffer_.data(), GL_UNSIGNED_BYTE, w, h);
  options.pixel_scale = supersample_;
  renderer_->draw(frame, camera, w, h, options);
  Image big;
  big.width = w;
  big.height = h;
  big.rgb.resize(static_cast<size_t>(w) * static_cast<size_t>(h) * 3);
  for (int y = 0; y < h; ++y) {  // OSMesa's rows go bottom to top
    const unsigned char* src =
        &buffer_[4 * static_cast<size_t>(h - 1 - y) * static_cast<size_t>(w)];
    std::uint8_t* dst = big.pixel(0, y);
    for (int x = 0; x < w; ++x) {
      dst[3 * x] = src[4 * x];
      dst[3 * x + 1] = src[4 * x + 1];
      dst[3 * x + 2] = src[4 * x + 2];
    }
  }
  return downsample(big, supersample_);
}

Camera OffscreenRenderer::fitCamera(const FrameData& frame, RenderOptions options) const {
  const int w = width_ * supersample_, h = height_ * supersample_;
  options.pixel_scale = supersample_;
  return frameCamera(frame, double(sceneViewportWidth(w, h, options)) / h,
                     hudHeightFraction(frame, h, options));
}

}  // namespace torsion::render
