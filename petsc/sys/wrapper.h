/* What mpfem's PETSc wrapper (the `petsc` crate) uses: vectors, matrices, linear solvers. */
#include <petscksp.h>
