// Layering probe (tests/CMakeLists: layering_*): compiled as part of one layer with
// PROBE_HEADER set to a header of another layer. Including a layer that is below must compile;
// including one that is not must fail the build with "No such file or directory".
#include PROBE_HEADER
