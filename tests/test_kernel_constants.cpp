// The numbers the CPU kernels and their GLSL twins share reach the shaders as the very floats the CPU's float
// kernels use (drape/kernel_constants.hpp, gpu::layout::preamble).
#include <drape/gpu/layout.hpp>
#include <drape/kernel_constants.hpp>

#include <catch2/catch.hpp>

#include <cfloat>
#include <cstdlib>
#include <string>

namespace {

/// The text of `#define name value` in the preamble, or empty.
std::string defined(const std::string& preamble, const std::string& name) {
  const std::string key = "#define " + name + " ";
  const auto at = preamble.find(key);
  if (at == std::string::npos) return {};
  const auto end = preamble.find('\n', at);
  return preamble.substr(at + key.size(), end - at - key.size());
}

/// GLSL's reading of a float literal: the nearest float (parentheses around a negative value dropped).
float asFloat(std::string text) {
  if (!text.empty() && text.front() == '(') text = text.substr(1, text.size() - 2);
  return std::strtof(text.c_str(), nullptr);
}

}  // namespace

TEST_CASE("every shared constant reaches the shaders as the float the CPU kernels use", "[constants]") {
  namespace c = drape::constants;
  const std::string p = drape::gpu::layout::preamble();
  const struct {
    const char* name;
    double value;
  } reals[] = {{"DRAPE_MERGE_COS", c::kMergeCos},
               {"DRAPE_FEASIBLE_SLACK", c::kFeasibleSlack},
               {"DRAPE_PARALLEL_PLANES", c::kParallelPlanes},
               {"DRAPE_CORNER_DETERMINANT", c::kCornerDeterminant},
               {"DRAPE_REACH", c::kReach},
               {"DRAPE_FACE_MOVE_CAP", c::kFaceMoveCap},
               {"DRAPE_FACE_SPREAD", c::kFaceSpread},
               {"DRAPE_EIGEN_NEGLIGIBLE", c::kEigenNegligible},
               {"DRAPE_FACE_SEARCH_GAP", c::kFaceSearchGap},
               {"DRAPE_HELD_POINT_SLACK", c::kHeldPointSlack},
               {"DRAPE_FACE_CONTACT_SLACK", c::kFaceContactSlack},
               {"DRAPE_FACE_CONTACT_ROUNDING", c::kFaceContactRoundings * double(FLT_EPSILON)},
               {"DRAPE_CUT_SLACK", c::kCutSlack},
               {"DRAPE_FLAT_SINE2", c::kFlatSine2},
               {"DRAPE_CORNER_CULL_SLACK", c::kCornerCullSlack},
               {"DRAPE_PARALLEL_SINE2", c::kParallelSine2},
               {"DRAPE_MIN_DESCENT_STEP", c::kMinDescentStep},
               {"DRAPE_GRID_LIPSCHITZ", c::kGridLipschitz},
               {"DRAPE_FEATURE_BARYCENTRIC", c::kFeatureBarycentric},
               {"DRAPE_FEATURE_INTERIOR_COS", c::kFeatureInteriorCos},
               {"DRAPE_FEATURE_EDGE_SINE", c::kFeatureEdgeSine},
               {"DRAPE_FEATURE_MIN_RATE", c::kFeatureMinRate},
               {"DRAPE_PINCH_RATE", c::kPinchRate},
               {"DRAPE_PINCH_OPPOSING_COS", c::kPinchOpposingCos},
               {"DRAPE_SPACER_GAP", c::kSpacerGap},
               {"DRAPE_SPLIT_GRAM_MIN", c::kSplitGramMin},
               {"DRAPE_LINE_MIN_ALONG", c::kLineMinAlong},
               {"DRAPE_ENERGY_MIN_DISPLACEMENT2", c::kEnergyMinDisplacement2}};
  for (const auto& r : reals) {
    const std::string text = defined(p, r.name);
    INFO(r.name << " is defined as '" << text << "'");
    REQUIRE(!text.empty());
    CHECK(text.find_first_of(".e") != std::string::npos);  // a float literal, not an int
    CHECK(asFloat(text) == float(r.value));
  }
  CHECK(defined(p, "DRAPE_CONTACT_SLOTS") == std::to_string(c::kContactSlots));
  CHECK(defined(p, "DRAPE_LEAST_SQUARES_PASSES") == std::to_string(c::kLeastSquaresPasses));
  CHECK(defined(p, "DRAPE_EIGEN_SWEEPS") == std::to_string(c::kEigenSweeps));
  CHECK(defined(p, "DRAPE_MAX_CUTS") == std::to_string(c::kMaxCuts));
  CHECK(defined(p, "DRAPE_GRID_SEARCH_DEPTH") == std::to_string(c::kGridSearchDepth));
  CHECK(defined(p, "DRAPE_GRID_SEARCH_BUDGET") == std::to_string(c::kGridSearchBudget));
  CHECK(defined(p, "DRAPE_SWEEP_STEPS") == std::to_string(c::kSweepSteps));
  CHECK(defined(p, "DRAPE_FACE_SWEEP_STEPS") == std::to_string(c::kFaceSweepSteps));
  CHECK(defined(p, "DRAPE_FEATURE_NEWTON_STEPS") == std::to_string(c::kFeatureNewtonSteps));
}
