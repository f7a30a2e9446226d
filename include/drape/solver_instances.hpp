#pragma once
// The built-in solvers and the meters for them (drape/metrics.hpp), compiled here: include this in one source
// file of a program that defines DRAPE_EXTERN_SOLVERS in all of them (drape/solver.hpp), so the other files
// do not compile them again.

#include <drape/metrics.hpp>
#include <drape/solver.hpp>

template class drape::SolverFront<drape::Solver<float>, float, DRAPE_BUILT_IN_SHAPES>;
template class drape::BasicSolver<float, DRAPE_BUILT_IN_SHAPES>;
template class drape::SolverFront<drape::Solver<double>, double, DRAPE_BUILT_IN_SHAPES>;
template class drape::BasicSolver<double, DRAPE_BUILT_IN_SHAPES>;
template drape::PenetrationStats drape::penetration(const drape::Solver<float>&, int);
template drape::PenetrationStats drape::penetration(const drape::Solver<double>&, int);
template void drape::TrembleMeter::frame(const drape::Solver<float>&, double, bool);
template void drape::TrembleMeter::frame(const drape::Solver<double>&, double, bool);
