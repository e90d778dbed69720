# Writes the tool version's source file (cmake -DSOURCE_DIR=... -DBINARY_DIR=... -DPROJECT_VERSION=...
# -P version_source.cmake): `git describe` of the checkout, run at every build (not only at configure
# time, which would leave a rebuilt binary recording the commit it was configured at). configure_file
# rewrites the file only when its text changes, so an unchanged checkout recompiles nothing.
execute_process(COMMAND git describe --always --dirty --tags
                WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE TBDRSIM_GIT_DESCRIBE OUTPUT_STRIP_TRAILING_WHITESPACE
                ERROR_QUIET)
if(NOT TBDRSIM_GIT_DESCRIBE)
  set(TBDRSIM_GIT_DESCRIBE "unknown")
endif()
configure_file(${SOURCE_DIR}/sim/app/version.cpp.in ${BINARY_DIR}/generated/tbdrsim_version.cpp @ONLY)
