# FindCHOLMOD: SuiteSparse 5.x on Debian ships neither a CMake config nor a pkg-config file
# (Debian 12: libsuitesparse-dev 5.12), so find the headers and the libraries CHOLMOD links by hand.
# Defines CHOLMOD_FOUND and the imported target SuiteSparse::CHOLMOD.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
set(_cholmod_libs cholmod amd camd colamd ccolamd suitesparseconfig metis)
set(CHOLMOD_LIBRARIES "")
foreach(_lib IN LISTS _cholmod_libs)
  find_library(CHOLMOD_${_lib}_LIBRARY NAMES ${_lib})
  if(CHOLMOD_${_lib}_LIBRARY)
    list(APPEND CHOLMOD_LIBRARIES ${CHOLMOD_${_lib}_LIBRARY})
  else()
    list(APPEND _cholmod_missing ${_lib})
  endif()
endforeach()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(CHOLMOD
  REQUIRED_VARS CHOLMOD_INCLUDE_DIR CHOLMOD_cholmod_LIBRARY CHOLMOD_suitesparseconfig_LIBRARY
  REASON_FAILURE_MESSAGE "install the Debian packages libsuitesparse-dev and libmetis-dev (scripts/install-deps.sh)")
if(CHOLMOD_FOUND AND NOT TARGET SuiteSparse::CHOLMOD)
  add_library(SuiteSparse::CHOLMOD INTERFACE IMPORTED)
  set_target_properties(SuiteSparse::CHOLMOD PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "${CHOLMOD_LIBRARIES}")
endif()
mark_as_advanced(CHOLMOD_INCLUDE_DIR)
