// The built-in solvers, compiled once for every test, sample and bench program (each defines
// DRAPE_EXTERN_SOLVERS; see drape/solver.hpp): Solver<double> here, Solver<float> beside it, so the two build
// in parallel.
#define DRAPE_SOLVER_INSTANCES_SCALAR double
#include <drape/solver_instances.hpp>
