#pragma once
// The built-in solvers and the meters for them (drape/metrics.hpp), compiled here: include this in one source
// file of a program that defines DRAPE_EXTERN_SOLVERS in all of them (drape/solver.hpp), so the other files
// do not compile them again. To compile the two scalars in two files that build side by side, define
// DRAPE_SOLVER_INSTANCES_SCALAR as float before including this in one and as double in the other.

#include <drape/metrics.hpp>
#include <drape/solver.hpp>

#define DRAPE_DETAIL_SOLVER_INSTANCES(S)                                                   \
  template class drape::SolverFront<drape::Solver<S>, S, DRAPE_BUILT_IN_SHAPES>;          \
  template class drape::BasicSolver<S, DRAPE_BUILT_IN_SHAPES>;                            \
  template drape::PenetrationStats drape::penetration(const drape::Solver<S>&, int);      \
  template void drape::TrembleMeter::frame(const drape::Solver<S>&, double, bool);

#ifdef DRAPE_SOLVER_INSTANCES_SCALAR
DRAPE_DETAIL_SOLVER_INSTANCES(DRAPE_SOLVER_INSTANCES_SCALAR)
#else
DRAPE_DETAIL_SOLVER_INSTANCES(float)
DRAPE_DETAIL_SOLVER_INSTANCES(double)
#endif
#undef DRAPE_DETAIL_SOLVER_INSTANCES
