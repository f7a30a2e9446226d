#pragma once
// Wavefront OBJ files to and from TriangleMesh. Optional: this is the one drape header with a compiled
// dependency, tinyobjloader (Debian: libtinyobjloader-dev), kept out of the umbrella header so the core stays
// header-only. Link the double-precision build, which also defines TINYOBJLOADER_USE_DOUBLE:
//   find_package(tinyobjloader CONFIG REQUIRED)
//   target_link_libraries(app PRIVATE drape::drape tinyobjloader::tinyobjloader_double)
// (tinyobjloader::tinyobjloader works too, but reads coordinates in float.)

#include <drape/sdf/mesh.hpp>

#include <tiny_obj_loader.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>

namespace drape {

namespace detail {

/// Throws drape::Error naming the line of the first vertex ('v') line of the OBJ text whose coordinates are not
/// three finite numbers: the parser would read 'nan' or 'x' as 0 and the mesh would fail later for another
/// reason.
inline void checkObjVertices(std::istream& in, const std::string& path) {
  std::string line;
  for (long number = 1; std::getline(in, line); ++number) {
    if (line.size() < 2 || line[0] != 'v' || (line[1] != ' ' && line[1] != '\t')) continue;
    std::istringstream words(line.substr(2));
    std::string word;
    for (int k = 0; k < 3; ++k) {
      const bool read = static_cast<bool>(words >> word);
      // from_chars, unlike strtod, raises no floating-point exception (a program may trap them).
      const char* first = word.data() + (read && word[0] == '+' ? 1 : 0);
      const char* last = word.data() + word.size();
      double value = 0;
      const auto [end, status] = std::from_chars(first, read ? last : first, value);
      require(read && status == std::errc() && end == last && std::isfinite(value), [&] {
        return "OBJ file '" + path + "', line " + std::to_string(number) + ": vertex coordinate " +
               std::to_string(k + 1) + (read ? " '" + word + "' is not a finite number in double's range" : " is missing");
      });
    }
  }
}

}  // namespace detail

/// Reads the vertices and faces of every object in an OBJ file into one mesh (polygons become triangle
/// fans; normals, texture coordinates and materials are ignored). Throws drape::Error naming the file when it
/// is a directory, cannot be read or parsed, has a vertex whose coordinates are not finite numbers (naming the
/// line), has no faces, or refers to a vertex it does not define. The mesh is not checked
/// for closedness here: buildDistanceGrid does that.
inline TriangleMesh loadObj(const std::string& path) {
  std::error_code error;
  detail::require(!std::filesystem::is_directory(path, error), "OBJ path '" + path + "' is a directory, not a file");
  {
    std::ifstream in(path);
    if (in) detail::checkObjVertices(in, path);  // an unreadable file is reported by the parser below
  }
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  const bool ok = reader.ParseFromFile(path, config);
  std::string why = reader.Error();
  while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
  detail::require(ok && reader.Valid(), "cannot load OBJ file '" + path + "': " + (why.empty() ? "parse error" : why));

  TriangleMesh mesh;
  const auto& xyz = reader.GetAttrib().vertices;
  mesh.vertices.reserve(xyz.size() / 3);
  for (std::size_t i = 0; i + 2 < xyz.size(); i += 3)
    mesh.vertices.emplace_back(double(xyz[i]), double(xyz[i + 1]), double(xyz[i + 2]));
  const Index nv = mesh.vertexCount();
  for (const auto& shape : reader.GetShapes()) {
    const auto& m = shape.mesh;
    std::size_t next = 0;
    for (std::size_t f = 0; f < m.num_face_vertices.size(); ++f) {
      const std::size_t corners = m.num_face_vertices[f];
      detail::require(corners == 3, "OBJ file '" + path + "': face " + std::to_string(f) + " of object '" + shape.name +
                                        "' has " + std::to_string(corners) + " corners after triangulation");
      std::array<Index, 3> tri{};
      for (int k = 0; k < 3; ++k) {
        const int v = m.indices[next + std::size_t(k)].vertex_index;
        detail::require(v >= 0 && v < nv, "OBJ file '" + path + "': face " + std::to_string(f) + " of object '" +
                                              shape.name + "' refers to vertex " + std::to_string(v + 1) +
                                              ", but the file defines " + std::to_string(nv));
        tri[k] = Index(v);
      }
      mesh.triangles.push_back(tri);
      next += corners;
    }
  }
  detail::require(!mesh.triangles.empty(), "OBJ file '" + path + "' has no faces");
  return mesh;
}

/// Writes `mesh` as an OBJ file (vertices with 17 significant digits, so a double round-trips exactly).
/// Throws drape::Error naming the file when it cannot be written.
inline void saveObj(const TriangleMesh& mesh, const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  detail::require(file != nullptr, "cannot open OBJ file '" + path + "' for writing");
  bool ok = std::fprintf(file, "# drape TriangleMesh: %d vertices, %d triangles\n", mesh.vertexCount(),
                         mesh.triangleCount()) > 0;
  for (const auto& v : mesh.vertices) ok = ok && std::fprintf(file, "v %.17g %.17g %.17g\n", v.x(), v.y(), v.z()) > 0;
  for (const auto& f : mesh.triangles) ok = ok && std::fprintf(file, "f %d %d %d\n", f[0] + 1, f[1] + 1, f[2] + 1) > 0;
  ok = (std::fclose(file) == 0) && ok;
  detail::require(ok, "cannot write OBJ file '" + path + "'");
}

}  // namespace drape
