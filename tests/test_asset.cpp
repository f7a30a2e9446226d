#include <drape/drape.hpp>
#include <catch2/catch.hpp>
TEST_CASE("grid asset", "[asset]") {
  drape::GridDesc g; g.nx = 4; g.ny = 3;
  auto a = drape::ClothAsset<float>::grid(g);
  CHECK(a.vertexCount() == 12);
  CHECK(a.faceCount() == 12);
}
