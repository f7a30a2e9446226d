#pragma once
// A headless OpenGL 4.5 core context for the compute kernels (docs/design.md §9), made one of two ways:
// - EGL on its device platform, surfaceless: a hardware device when the machine has one, else Mesa's software
//   device (llvmpipe);
// - OSMesa: Mesa's llvmpipe, no GPU and no display needed (the CI path).
// Both libraries are opened at run time (dlopen), so a program that uses drape::gpu links neither, runs where
// only one is installed, and says which is missing where neither is. GL's functions come through glad, loaded
// from the context's own GetProcAddress; they are process-wide, so making a context of the other kind current
// loads them again.
//
// Backend::Auto takes, in order: an EGL hardware device, OSMesa, EGL's software device. The environment
// variable DRAPE_GPU_BACKEND (egl or osmesa) overrides Auto, so a test or a sample can be pointed at either
// without a rebuild.

// EGL's headers must come before glad's GL header (both define the Khronos platform macros).
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <glad/gl.h>

#include <drape/math.hpp>  // drape::Error

#include <dlfcn.h>

#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace drape::gpu {

enum class Backend { Auto, Egl, OSMesa };

inline const char* toString(Backend b) {
  switch (b) {
    case Backend::Auto: return "auto";
    case Backend::Egl: return "egl";
    case Backend::OSMesa: return "osmesa";
  }
  return "?";
}
/// The Backend named by toString, or throws drape::Error.
inline Backend backendFromString(const std::string& name) {
  for (Backend b : {Backend::Auto, Backend::Egl, Backend::OSMesa})
    if (name == toString(b)) return b;
  throw Error("drape::gpu: unknown backend '" + name + "' (auto, egl, osmesa)");
}

namespace detail {

// The few OSMesa declarations drape needs (GL/osmesa.h includes GL/gl.h, which glad's header replaces).
struct OSMesaContextRec;
using OSMesaContextHandle = OSMesaContextRec*;
inline constexpr int kOSMesaFormat = 0x22, kOSMesaDepthBits = 0x30, kOSMesaProfile = 0x33,
                     kOSMesaCoreProfile = 0x34, kOSMesaMajor = 0x36, kOSMesaMinor = 0x37;

/// A shared library opened for the process's lifetime (closing GL drivers at exit is a known source of crashes).
inline void* openLibrary(std::initializer_list<const char*> names, std::string& tried) {
  for (const char* n : names) {
    if (void* h = dlopen(n, RTLD_NOW | RTLD_LOCAL)) return h;
    tried += std::string(tried.empty() ? "" : ", ") + n;
  }
  return nullptr;
}

template <class F> F symbol(void* lib, const char* name) {
  return reinterpret_cast<F>(dlsym(lib, name));
}

/// Which context's GetProcAddress the process's GL functions came from (0 none, else a Backend).
inline int& loadedFrom() {
  static int which = 0;
  return which;
}

}  // namespace detail

/// A GL 4.5 core context with no window. Not copyable; current on the thread that made it until another is.
class Context {
 public:
  /// Makes the context, and makes it current. Throws drape::Error naming what is missing (a library, an EGL
  /// device, a GL version) when none of the asked kind can be made.
  explicit Context(Backend backend = Backend::Auto) {
    if (backend == Backend::Auto) {
      if (const char* env = std::getenv("DRAPE_GPU_BACKEND"); env && *env) backend = backendFromString(env);
    }
    std::string why;
    if (backend == Backend::Egl) {
      if (!makeEgl(false, why)) throw Error("drape::gpu: no EGL context: " + why);
    } else if (backend == Backend::OSMesa) {
      if (!makeOSMesa(why)) throw Error("drape::gpu: no OSMesa context: " + why);
    } else {
      std::string eglWhy, osWhy, softWhy;
      if (!makeEgl(true, eglWhy) && !makeOSMesa(osWhy) && !makeEgl(false, softWhy))
        throw Error("drape::gpu: no GL 4.3+ context could be made. EGL hardware device: " + eglWhy +
                    "; OSMesa: " + osWhy + "; EGL software device: " + softWhy);
    }
    makeCurrent();
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 43) {
      release();
      throw Error("drape::gpu: the context gives OpenGL " + std::to_string(major) + "." + std::to_string(minor) +
                  "; compute shaders need 4.3");
    }
    renderer_ = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    version_ = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  ~Context() { release(); }

  Backend backend() const { return backend_; }
  /// GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
  const std::string& renderer() const { return renderer_; }
  /// GL_VERSION.
  const std::string& version() const { return version_; }
  /// Whether the renderer is a CPU (llvmpipe, softpipe): right for correctness, not for timing.
  bool software() const { return renderer_.find("llvmpipe") != std::string::npos || renderer_.find("softpipe") != std::string::npos; }

  /// Makes this context current on the calling thread (and loads GL's functions from it if the process's
  /// came from a context of the other kind).
  void makeCurrent() {
    if (backend_ == Backend::Egl) {
      if (!egl_.makeCurrent(egl_.display, EGL_NO_SURFACE, EGL_NO_SURFACE, egl_.context))
        throw Error("drape::gpu: eglMakeCurrent failed");
    } else {
      if (!os_.makeCurrent(os_.context, pixel_.data(), GL_UNSIGNED_BYTE, 1, 1))
        throw Error("drape::gpu: OSMesaMakeCurrent failed");
    }
    if (detail::loadedFrom() != int(backend_)) {
      const int version = backend_ == Backend::Egl ? gladLoadGLUserPtr(&Context::eglProc, this)
                                                   : gladLoadGLUserPtr(&Context::osProc, this);
      if (version == 0) throw Error("drape::gpu: glad could not load the GL functions");
      detail::loadedFrom() = int(backend_);
    }
  }

 private:
  struct Egl {
    void* lib = nullptr;
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
    PFNEGLGETPROCADDRESSPROC getProc = nullptr;
    PFNEGLMAKECURRENTPROC makeCurrent = nullptr;
    PFNEGLDESTROYCONTEXTPROC destroyContext = nullptr;
    PFNEGLTERMINATEPROC terminate = nullptr;
  };
  struct OSMesa {
    void* lib = nullptr;
    detail::OSMesaContextHandle context = nullptr;
    GLADapiproc (*getProc)(const char*) = nullptr;
    GLboolean (*makeCurrent)(detail::OSMesaContextHandle, void*, GLenum, GLsizei, GLsizei) = nullptr;
    void (*destroy)(detail::OSMesaContextHandle) = nullptr;
  };

  static GLADapiproc eglProc(void* self, const char* name) {
    return reinterpret_cast<GLADapiproc>(static_cast<Context*>(self)->egl_.getProc(name));
  }
  static GLADapiproc osProc(void* self, const char* name) { return static_cast<Context*>(self)->os_.getProc(name); }

  /// EGL's device platform, a device chosen by `hardware` (one that is not Mesa's software device, or the
  /// software one), with a configless, surfaceless 4.5 core context. Returns false and says why otherwise.
  bool makeEgl(bool hardware, std::string& why) {
    std::string tried;
    void* lib = detail::openLibrary({"libEGL.so.1", "libEGL.so"}, tried);
    if (!lib) return why = "cannot open " + tried + " (Debian: libegl1 and libegl-mesa0)", false;
    Egl e;
    e.lib = lib;
    e.getProc = detail::symbol<PFNEGLGETPROCADDRESSPROC>(lib, "eglGetProcAddress");
    if (!e.getProc) return why = "libEGL has no eglGetProcAddress", false;
    auto proc = [&](const char* name) { return reinterpret_cast<void*>(e.getProc(name)); };
    auto queryDevices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(proc("eglQueryDevicesEXT"));
    auto deviceString = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(proc("eglQueryDeviceStringEXT"));
    auto platformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(proc("eglGetPlatformDisplayEXT"));
    auto initialize = reinterpret_cast<PFNEGLINITIALIZEPROC>(proc("eglInitialize"));
    auto bindApi = reinterpret_cast<PFNEGLBINDAPIPROC>(proc("eglBindAPI"));
    auto createContext = reinterpret_cast<PFNEGLCREATECONTEXTPROC>(proc("eglCreateContext"));
    auto getError = reinterpret_cast<PFNEGLGETERRORPROC>(proc("eglGetError"));
    e.makeCurrent = reinterpret_cast<PFNEGLMAKECURRENTPROC>(proc("eglMakeCurrent"));
    e.destroyContext = reinterpret_cast<PFNEGLDESTROYCONTEXTPROC>(proc("eglDestroyContext"));
    e.terminate = reinterpret_cast<PFNEGLTERMINATEPROC>(proc("eglTerminate"));
    if (!queryDevices || !deviceString || !platformDisplay)
      return why = "EGL lacks the device platform (EGL_EXT_device_enumeration, EGL_EXT_platform_device)", false;
    if (!initialize || !bindApi || !createContext || !getError || !e.makeCurrent || !e.destroyContext || !e.terminate)
      return why = "EGL lacks a core function", false;
    EGLint count = 0;
    if (!queryDevices(0, nullptr, &count) || count <= 0) return why = "EGL lists no device", false;
    std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
    queryDevices(count, devices.data(), &count);
    std::string hexes;
    for (EGLint k = 0; k < count; ++k) {
      const char* ext = deviceString(devices[std::size_t(k)], EGL_EXTENSIONS);
      const bool soft = ext && std::strstr(ext, "EGL_MESA_device_software");
      if (soft == hardware) continue;
      EGLDisplay display = platformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[std::size_t(k)], nullptr);
      EGLint major = 0, minor = 0;
      if (display == EGL_NO_DISPLAY || !initialize(display, &major, &minor)) {
        hexes += " device " + std::to_string(k) + ": eglInitialize failed;";
        continue;
      }
      bindApi(EGL_OPENGL_API);
      const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                   EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
      EGLContext context = createContext(display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
      if (context == EGL_NO_CONTEXT) {
        hexes += " device " + std::to_string(k) + ": no 4.5 core context (EGL error " + std::to_string(getError()) + ");";
        e.terminate(display);
        continue;
      }
      e.display = display;
      e.context = context;
      egl_ = e;
      backend_ = Backend::Egl;
      return true;
    }
    why = (hardware ? "no hardware device among " : "no software device among ") + std::to_string(count) +
          " EGL devices" + (hexes.empty() ? "" : ":" + hexes);
    return false;
  }

  /// An OSMesa 4.5 core context (Mesa's llvmpipe). Returns false and says why otherwise.
  bool makeOSMesa(std::string& why) {
    std::string tried;
    void* lib = detail::openLibrary({"libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"}, tried);
    if (!lib) return why = "cannot open " + tried + " (Debian: libosmesa6)", false;
    OSMesa o;
    o.lib = lib;
    o.getProc = detail::symbol<GLADapiproc (*)(const char*)>(lib, "OSMesaGetProcAddress");
    o.makeCurrent = detail::symbol<decltype(o.makeCurrent)>(lib, "OSMesaMakeCurrent");
    o.destroy = detail::symbol<decltype(o.destroy)>(lib, "OSMesaDestroyContext");
    auto create = detail::symbol<detail::OSMesaContextHandle (*)(const int*, detail::OSMesaContextHandle)>(
        lib, "OSMesaCreateContextAttribs");
    if (!o.getProc || !o.makeCurrent || !o.destroy || !create)
      return why = "libOSMesa lacks OSMesaCreateContextAttribs (Mesa 11.2 or newer needed)", false;
    const int attributes[] = {detail::kOSMesaFormat, int(GL_RGBA), detail::kOSMesaDepthBits, 0,
                              detail::kOSMesaProfile, detail::kOSMesaCoreProfile, detail::kOSMesaMajor, 4,
                              detail::kOSMesaMinor, 5, 0};
    o.context = create(attributes, nullptr);
    if (!o.context) return why = "OSMesaCreateContextAttribs gave no 4.5 core context", false;
    os_ = o;
    pixel_.assign(4, 0);
    backend_ = Backend::OSMesa;
    return true;
  }

  void release() {
    if (backend_ == Backend::Egl && egl_.context != EGL_NO_CONTEXT) {
      egl_.makeCurrent(egl_.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      egl_.destroyContext(egl_.display, egl_.context);
      egl_.context = EGL_NO_CONTEXT;
    } else if (backend_ == Backend::OSMesa && os_.context) {
      os_.destroy(os_.context);
      os_.context = nullptr;
    }
  }

  Backend backend_ = Backend::Auto;
  Egl egl_;
  OSMesa os_;
  std::vector<unsigned char> pixel_;  ///< OSMesa's 1x1 colour buffer (the kernels draw nothing)
  std::string renderer_, version_;
};

}  // namespace drape::gpu
