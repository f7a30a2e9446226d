#pragma once
// Compute programs and storage buffers, each owning its GL object (a context must be current while they live).

#include <drape/gpu/context.hpp>
#include <drape/gpu/layout.hpp>
#include <drape/gpu/shader_sources.hpp>

#include <algorithm>
#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace drape::gpu {

/// A compute program: layout::preamble(defines), shaders/common.glsl, then the kernel's source (its line
/// numbers in the compiler's messages are the file's). Throws drape::Error with the compiler's or linker's log,
/// naming the kernel, if it does not build.
class Program {
 public:
  Program() = default;
  Program(std::string_view name, std::string_view source, const std::string& defines = {}) : name_(name) {
    const std::string text = layout::preamble(defines) + "#line 1 1\n" + std::string(shaders::common_glsl) +
                             "\n#line 1 0\n" + std::string(source);
    const char* ptr = text.c_str();
    const GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
    glShaderSource(shader, 1, &ptr, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      const std::string log = infoLog(shader, false);
      glDeleteShader(shader);
      throw Error("drape::gpu: kernel '" + name_ + "' does not compile:\n" + log);
    }
    id_ = glCreateProgram();
    glAttachShader(id_, shader);
    glLinkProgram(id_);
    glDeleteShader(shader);
    glGetProgramiv(id_, GL_LINK_STATUS, &ok);
    if (!ok) {
      const std::string log = infoLog(id_, true);
      glDeleteProgram(id_);
      id_ = 0;
      throw Error("drape::gpu: kernel '" + name_ + "' does not link:\n" + log);
    }
  }
  Program(Program&& o) noexcept : id_(std::exchange(o.id_, 0)), name_(std::move(o.name_)) {}
  Program& operator=(Program&& o) noexcept {
    std::swap(id_, o.id_);
    std::swap(name_, o.name_);
    return *this;
  }
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;
  ~Program() {
    if (id_) glDeleteProgram(id_);
  }

  GLuint id() const { return id_; }
  const std::string& name() const { return name_; }

  void set(layout::Uniform u, unsigned value) const { glProgramUniform1ui(id_, u, value); }
  void set(layout::Uniform u, float value) const { glProgramUniform1f(id_, u, value); }
  void set(layout::Uniform u, float x, float y) const { glProgramUniform2f(id_, u, x, y); }
  void set(layout::Uniform u, float x, float y, float z) const { glProgramUniform3f(id_, u, x, y, z); }

  /// Runs the kernel over `items` invocations (whole workgroups; each kernel skips those past its count).
  void dispatch(std::size_t items) const {
    if (items == 0) return;
    glUseProgram(id_);
    glDispatchCompute(GLuint((items + layout::kWorkgroup - 1) / layout::kWorkgroup), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }

  /// Runs the kernel over the workgroups an earlier kernel wrote to buffer `commands` at byte `offset` (x, y, z as
  /// three uints; x = 0: nothing runs). A pass that has nothing to do then costs no invocation, and nothing is
  /// read back to learn it.
  void dispatchIndirect(GLuint commands, GLintptr offset) const {
    glMemoryBarrier(GL_COMMAND_BARRIER_BIT);
    glUseProgram(id_);
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, commands);
    glDispatchComputeIndirect(offset);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }

 private:
  static std::string infoLog(GLuint object, bool program) {
    GLint length = 0;
    if (program)
      glGetProgramiv(object, GL_INFO_LOG_LENGTH, &length);
    else
      glGetShaderiv(object, GL_INFO_LOG_LENGTH, &length);
    std::string log(std::size_t(std::max(length, 1)), '\0');
    if (program)
      glGetProgramInfoLog(object, length, nullptr, log.data());
    else
      glGetShaderInfoLog(object, length, nullptr, log.data());
    return log;
  }

  GLuint id_ = 0;
  std::string name_;
};

/// A shader storage buffer of `T`s, bound to one binding point when asked.
template <class T> class Buffer {
 public:
  Buffer() = default;
  explicit Buffer(const std::vector<T>& data) { assign(data); }
  Buffer(Buffer&& o) noexcept : id_(std::exchange(o.id_, 0)), size_(std::exchange(o.size_, 0)) {}
  Buffer& operator=(Buffer&& o) noexcept {
    std::swap(id_, o.id_);
    std::swap(size_, o.size_);
    return *this;
  }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  ~Buffer() {
    if (id_) glDeleteBuffers(1, &id_);
  }

  /// Replaces the contents (and the size).
  void assign(const std::vector<T>& data) {
    if (!id_) glCreateBuffers(1, &id_);
    size_ = data.size();
    // An empty buffer still gets a few bytes: binding a zero-sized buffer is an error.
    glNamedBufferData(id_, GLsizeiptr(std::max<std::size_t>(size_ * sizeof(T), 16)), data.empty() ? nullptr : data.data(),
                      GL_DYNAMIC_COPY);
  }
  /// Overwrites the first data.size() elements.
  /// (Both wait for the shaders' writes before them: GL_BUFFER_UPDATE_BARRIER_BIT.)
  void write(const std::vector<T>& data) {
    if (data.empty()) return;
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glNamedBufferSubData(id_, 0, GLsizeiptr(data.size() * sizeof(T)), data.data());
  }
  std::vector<T> read() const { return read(0, size_); }
  /// Elements [first, first + count), which must lie in the buffer.
  std::vector<T> read(std::size_t first, std::size_t count) const {
    if (first > size_ || count > size_ - first)
      throw Error("drape::gpu: reading elements [" + std::to_string(first) + ", " + std::to_string(first + count) +
                  ") of a buffer of " + std::to_string(size_));
    std::vector<T> out(count);
    if (!count) return out;
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetNamedBufferSubData(id_, GLintptr(first * sizeof(T)), GLsizeiptr(count * sizeof(T)), out.data());
    return out;
  }
  void bind(layout::Binding b) const { glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, id_); }
  std::size_t size() const { return size_; }
  GLuint id() const { return id_; }

 private:
  GLuint id_ = 0;
  std::size_t size_ = 0;
};

}  // namespace drape::gpu
