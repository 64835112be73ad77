# FindPETSc: PETSc (Debian 12: petsc-dev, PETSc 3.18 with Open MPI) ships a pkg-config file,
# PETSc.pc, and no CMake config. Defines PETSc_FOUND, PETSc_VERSION and the imported target
# PETSc::PETSc (headers, PETSc and the MPI it was built with).
find_package(PkgConfig QUIET)
if(PKG_CONFIG_FOUND)
  pkg_check_modules(_PETSC QUIET PETSc)
endif()
set(PETSc_VERSION "${_PETSC_VERSION}")
# PETSc's headers include mpi.h, which Debian keeps in Open MPI's own include directory: the MPI C
# API through the C++ compiler (without the deprecated C++ bindings).
set(MPI_CXX_SKIP_MPICXX ON)
find_package(MPI QUIET COMPONENTS CXX)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(PETSc
  REQUIRED_VARS _PETSC_FOUND MPI_CXX_FOUND
  VERSION_VAR PETSc_VERSION
  REASON_FAILURE_MESSAGE "install the Debian packages petsc-dev and openmpi-bin (scripts/install-deps.sh)")
if(PETSc_FOUND AND NOT TARGET PETSc::PETSc)
  add_library(PETSc::PETSc INTERFACE IMPORTED)
  # PETSc's headers are system headers here: their own warnings are not ours to fix.
  set_target_properties(PETSc::PETSc PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${_PETSC_INCLUDE_DIRS}"
    INTERFACE_SYSTEM_INCLUDE_DIRECTORIES "${_PETSC_INCLUDE_DIRS}"
    INTERFACE_LINK_DIRECTORIES "${_PETSC_LIBRARY_DIRS}"
    INTERFACE_LINK_LIBRARIES "${_PETSC_LIBRARIES};MPI::MPI_CXX")
endif()
