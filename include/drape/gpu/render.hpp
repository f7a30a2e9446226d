#pragma once
// Offscreen pictures of a scene, drawn with the context the kernels run on: the cloth straight
// from the GPU solver's position buffer (or from CPU positions, uploaded), and solids as triangle meshes, flat
// shaded with a light over the camera's shoulder, both sides of the cloth lit. A frame is read back as RGBA8
// rows, top row first, for a PNG writer. The mesh shaders are shaders/draw_vert.glsl and draw_frag.glsl.

#include <drape/gpu/program.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace drape::gpu {

/// Where the camera is: world points (m), a vertical field of view (degrees).
struct Camera {
  Eigen::Vector3d eye{2, -2, 1.5};
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  double fovDeg = 40;
};

/// A triangle mesh to draw: world positions (m) and faces.
struct DrawMesh {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<Index, 3>> triangles;
};

class Renderer {
 public:
  /// A width x height colour and depth target on `context` (made current).
  Renderer(Context& context, int width, int height) : context_(&context), width_(width), height_(height) {
    drape::detail::require(width >= 16 && height >= 16 && width <= 8192 && height <= 8192,
                           "a picture must be 16 to 8192 pixels on a side (got " + std::to_string(width) + "x" +
                               std::to_string(height) + ")");
    context.makeCurrent();
    glCreateFramebuffers(1, &fbo_);
    glCreateRenderbuffers(2, rbo_);
    glNamedRenderbufferStorage(rbo_[0], GL_RGBA8, width, height);
    glNamedRenderbufferStorage(rbo_[1], GL_DEPTH_COMPONENT24, width, height);
    glNamedFramebufferRenderbuffer(fbo_, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rbo_[0]);
    glNamedFramebufferRenderbuffer(fbo_, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rbo_[1]);
    if (glCheckNamedFramebufferStatus(fbo_, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error("drape::gpu: the picture's framebuffer is incomplete");
    glCreateVertexArrays(1, &vao_);  // a core context draws only with a vertex array bound (this one has no attributes)
    program_ = link(std::string(shaders::draw_vert_glsl), std::string(shaders::draw_frag_glsl));
  }
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;
  ~Renderer() {
    glDeleteProgram(program_);
    glDeleteVertexArrays(1, &vao_);
    glDeleteFramebuffers(1, &fbo_);
    glDeleteRenderbuffers(2, rbo_);
  }

  int width() const { return width_; }
  int height() const { return height_; }

  /// Starts a frame: clears to a pale sky and sets the camera. Positions are drawn relative to the camera's
  /// target, so float keeps its precision far from the world's origin.
  void begin(const Camera& camera) {
    context_->makeCurrent();
    camera_ = camera;
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glViewport(0, 0, width_, height_);
    glClearColor(0.86f, 0.9f, 0.95f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    const Eigen::Vector3d f = (camera.target - camera.eye).normalized();
    const Eigen::Vector3d r = f.cross(camera.up).normalized(), u = r.cross(f);
    const double dist = (camera.target - camera.eye).norm();
    Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
    view.block<1, 3>(0, 0) = r.transpose();
    view.block<1, 3>(1, 0) = u.transpose();
    view.block<1, 3>(2, 0) = -f.transpose();
    view(2, 3) = -dist;  // the target is the origin of the drawn positions; the eye sits dist in front of it
    const double near = 0.01 * dist, far = 100 * dist;
    const double t = 1 / std::tan(0.5 * camera.fovDeg * EIGEN_PI / 180), aspect = double(width_) / height_;
    Eigen::Matrix4d proj = Eigen::Matrix4d::Zero();
    proj(0, 0) = t / aspect;
    proj(1, 1) = t;
    proj(2, 2) = -(far + near) / (far - near);
    proj(2, 3) = -2 * far * near / (far - near);
    proj(3, 2) = -1;
    const Eigen::Matrix4f m = (proj * view).cast<float>();
    glProgramUniformMatrix4fv(program_, 0, 1, GL_FALSE, m.data());
    const Eigen::Vector3f light = (0.6 * (camera.eye - camera.target).normalized() + Eigen::Vector3d(0.3, 0.2, 0.8)).normalized().cast<float>();
    glProgramUniform3f(program_, 3, light.x(), light.y(), light.z());
  }

  /// Draws triangles whose corners are read from a buffer of vec4 positions relative to `origin` (world, m):
  /// the GPU solver's own, without reading them back.
  void drawTriangles(const Buffer<layout::Vertex>& positions, const Eigen::Vector3d& origin,
                     const Buffer<std::array<std::uint32_t, 4>>& faces, const Eigen::Vector3f& colour,
                     bool checker = false) {
    const Eigen::Vector3f offset = (origin - camera_.target).cast<float>();
    glProgramUniform3f(program_, 1, offset.x(), offset.y(), offset.z());
    glProgramUniform3f(program_, 2, colour.x(), colour.y(), colour.z());
    glProgramUniform1ui(program_, 4, checker ? 1u : 0u);
    const Eigen::Vector3f world = origin.cast<float>();
    glProgramUniform3f(program_, 5, world.x(), world.y(), world.z());
    positions.bind(layout::kPositions);
    faces.bind(layout::kFaces);
    glUseProgram(program_);
    glBindVertexArray(vao_);
    glDrawArrays(GL_TRIANGLES, 0, GLsizei(3 * faces.size()));
  }

  /// Draws a mesh given on the CPU (world positions).
  void draw(const DrawMesh& mesh, const Eigen::Vector3f& colour, bool checker = false) {
    std::vector<layout::Vertex> p(mesh.positions.size());
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Eigen::Vector3f q = (mesh.positions[i] - camera_.target).cast<float>();
      p[i] = {q.x(), q.y(), q.z(), 0};
    }
    std::vector<std::array<std::uint32_t, 4>> f(mesh.triangles.size());
    for (std::size_t k = 0; k < f.size(); ++k)
      f[k] = {std::uint32_t(mesh.triangles[k][0]), std::uint32_t(mesh.triangles[k][1]), std::uint32_t(mesh.triangles[k][2]), 0};
    scratchPositions_.assign(p);
    scratchFaces_.assign(f);
    drawTriangles(scratchPositions_, camera_.target, scratchFaces_, colour, checker);
  }

  /// The frame as RGBA8, width * height * 4 bytes, top row first.
  std::vector<std::uint8_t> pixels() {
    context_->makeCurrent();
    std::vector<std::uint8_t> rgba(std::size_t(width_) * std::size_t(height_) * 4);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    const std::size_t row = std::size_t(width_) * 4;
    for (int y = 0; y < height_ / 2; ++y)  // GL's first row is the bottom one
      std::swap_ranges(rgba.begin() + std::ptrdiff_t(std::size_t(y) * row), rgba.begin() + std::ptrdiff_t(std::size_t(y + 1) * row),
                       rgba.begin() + std::ptrdiff_t(std::size_t(height_ - 1 - y) * row));
    return rgba;
  }

 private:
  static GLuint link(const std::string& vertex, const std::string& fragment) {
    auto compile = [](GLenum kind, const std::string& body, const char* name) {
      const std::string text = layout::preamble() + "#line 1 0\n" + body;
      const char* ptr = text.c_str();
      const GLuint s = glCreateShader(kind);
      glShaderSource(s, 1, &ptr, nullptr);
      glCompileShader(s);
      GLint ok = 0;
      glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
      if (!ok) {
        GLint length = 0;
        glGetShaderiv(s, GL_INFO_LOG_LENGTH, &length);
        std::string log(std::size_t(std::max(length, 1)), '\0');
        glGetShaderInfoLog(s, length, nullptr, log.data());
        glDeleteShader(s);
        throw Error(std::string("drape::gpu: shader '") + name + "' does not compile:\n" + log);
      }
      return s;
    };
    const GLuint vs = compile(GL_VERTEX_SHADER, vertex, "draw_vert"), fs = compile(GL_FRAGMENT_SHADER, fragment, "draw_frag");
    const GLuint p = glCreateProgram();
    glAttachShader(p, vs);
    glAttachShader(p, fs);
    glLinkProgram(p);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
      glDeleteProgram(p);
      throw Error("drape::gpu: the drawing program does not link");
    }
    return p;
  }

  Context* context_;
  int width_, height_;
  GLuint fbo_ = 0, rbo_[2] = {0, 0}, vao_ = 0, program_ = 0;
  Camera camera_;
  Buffer<layout::Vertex> scratchPositions_;
  Buffer<std::array<std::uint32_t, 4>> scratchFaces_;
};

}  // namespace drape::gpu
