#pragma once

namespace hooke {

/// Starts MPI (asking for MPI_THREAD_MULTIPLE, unless the host program started it) and PETSc, once
/// per process, with PETSc's error handler set to return codes with their messages, never to
/// print or abort; both are finalised at exit. Every use of PETSc or MPI in hooke starts here.
/// Built with HOOKE_WITH_PETSC only.
void start_petsc();

}  // namespace hooke
