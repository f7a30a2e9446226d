// The built-in solvers compiled once for the whole test binary (DRAPE_EXTERN_SOLVERS in every test source).
#include <drape/solver_instances.hpp>
