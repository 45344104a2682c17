# Finds SuiteSparse components (CHOLMOD, UMFPACK, ...) and defines imported targets
# SuiteSparse::<Component>. SuiteSparse 7 and later install CMake configs, which are tried first;
# Debian 12 ships SuiteSparse 5 without configs or .pc files, so the fallback looks for the
# headers (under include/suitesparse) and the library of each component directly.
# Usage: find_package(SuiteSparseDeb COMPONENTS CHOLMOD)
include(FindPackageHandleStandardArgs)
foreach(_comp IN LISTS SuiteSparseDeb_FIND_COMPONENTS)
  string(TOLOWER "${_comp}" _lower)
  if(NOT TARGET SuiteSparse::${_comp})
    find_package(${_comp} CONFIG QUIET)
  endif()
  if(TARGET SuiteSparse::${_comp})
    set(SuiteSparseDeb_${_comp}_FOUND TRUE)
    set(SuiteSparseDeb_INCLUDE_DIR "provided-by-config")
    continue()
  endif()
  find_path(SuiteSparseDeb_INCLUDE_DIR NAMES SuiteSparse_config.h PATH_SUFFIXES suitesparse)
  find_library(SuiteSparseDeb_${_comp}_LIBRARY NAMES ${_lower})
  if(SuiteSparseDeb_INCLUDE_DIR AND SuiteSparseDeb_${_comp}_LIBRARY)
    add_library(SuiteSparse::${_comp} UNKNOWN IMPORTED)
    set_target_properties(SuiteSparse::${_comp} PROPERTIES
      IMPORTED_LOCATION "${SuiteSparseDeb_${_comp}_LIBRARY}"
      INTERFACE_INCLUDE_DIRECTORIES "${SuiteSparseDeb_INCLUDE_DIR}")
    set(SuiteSparseDeb_${_comp}_FOUND TRUE)
  else()
    set(SuiteSparseDeb_${_comp}_FOUND FALSE)
  endif()
endforeach()
find_package_handle_standard_args(SuiteSparseDeb
  REQUIRED_VARS SuiteSparseDeb_INCLUDE_DIR HANDLE_COMPONENTS)
