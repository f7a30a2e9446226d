#pragma once
// drape: cloth that touches solids. Include this header for everything.

#include <drape/cloth/asset.hpp>
#include <drape/cloth/integrate.hpp>
#include <drape/cloth/state.hpp>
#include <drape/collision/pgd.hpp>
#include <drape/collision/response.hpp>
#include <drape/constraints/distance.hpp>
#include <drape/math.hpp>
#include <drape/metrics.hpp>
#include <drape/sdf/grid.hpp>
#include <drape/sdf/mesh.hpp>
#include <drape/sdf/shapes.hpp>
#include <drape/sdf/solid.hpp>
#include <drape/settings.hpp>
#include <drape/solver.hpp>
#include <drape/version.hpp>
