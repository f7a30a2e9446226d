// The built-in solvers, compiled once for every test, sample and bench program (each defines
// DRAPE_EXTERN_SOLVERS; see drape/solver.hpp).
#include <drape/solver_instances.hpp>
