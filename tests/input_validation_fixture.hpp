#pragma once
// Shared by the hostile-input tests (issue 16): tests/test_input_validation.cpp (the readers; the
// sanitizer subset builds it with the reader libraries only, docs/fuzzing.md) and
// tests/test_input_validation_cli.cpp (the same refusals through the command line: exit 2,
// file:line, nothing written). A small valid trace to make hostile variants of, and scratch files.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>
#include <utility>

#include "kernel/errors.hpp"
#include "scratch_dir.hpp"
#include "trace/trace.hpp"

namespace tbdr::input_validation {

namespace fs = std::filesystem;

/// A fresh scratch folder `name` of these tests.
inline fs::path dir_for(const std::string& name) { return testing_scratch::scratch_dir("input_validation", name); }

/// Writes `text` to `p`, creating its folder.
inline void write_file(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

// A small valid trace on the atrium at detail 1: `decl` is spliced in after the camera (lights,
// buffers) and `body` after the declarations (passes, dispatches).
inline std::string trace_text(const std::string& camera, const std::string& decl, const std::string& body) {
  return "tbdrsim-trace 2\n"                                                                   // 1
         "scene atrium detail=1\n"                                                             // 2
         "frame width=64 height=64 samples=1\n"                                                // 3
         + camera + "\n" +                                                                     // 4
         decl +
         "shader s alu_ops=4 tex_fetches=0 varyings=4 light_alu_ops=0 light_source=none color_outputs=1\n"
         "pipeline p shader=s depth_test=yes depth_write=yes blend=off cull=back\n" + body;
}
inline const std::string kCamera = "camera eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100";
inline const std::string kPass =
    "pass main\n"
    "  attachment color format=rgba8 samples=1 load=clear store=store usage=color\n"
    "  attachment depth format=d24s8 samples=1 load=clear store=dont_care usage=depth transient=no\n"
    "  draw scene pipeline=p\n"
    "end\n";

// Parsing `text` throws an InputError at "t.trace:line" whose message holds every `tokens`.
inline void expect_refused(const std::string& text, int line, std::initializer_list<std::string> tokens) {
  std::istringstream in(text);
  try {
    parse_trace(in, "t.trace");
    ADD_FAILURE() << "accepted; expected an error at line " << line;
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.where(), "t.trace:" + std::to_string(line)) << what;
    for (const auto& t : tokens) EXPECT_NE(what.find(t), std::string::npos) << "'" << t << "' not in: " << what;
  }
}

/// The trace of `text`, read as t.trace.
inline Trace parse(const std::string& text) {
  std::istringstream in(text);
  return parse_trace(in, "t.trace");
}

/// A pass (lines 7-11 of trace_text's trace) whose draw names a sub-mesh the atrium lacks (line 10).
inline const std::string kDrawOfAMissingSubMesh =
    "pass main\n"
    "  attachment color format=rgba8 samples=1 load=clear store=store usage=color\n"
    "  attachment depth format=d24s8 samples=1 load=clear store=dont_care usage=depth\n"
    "  draw scene pipeline=p submesh=no_such_mesh\n"  // line 10
    "end\n";

/// Debian's assimp-testmodels (apt install assimp-testmodels): glTF files broken on purpose.
inline const fs::path kAssimpGltf2 = "/usr/share/assimp/models/glTF2";
/// Each broken file under kAssimpGltf2 and a field its refusal names.
inline constexpr std::pair<const char*, const char*> kAssimpBrokenGltf[] = {
    {"wrongTypes/badArray.gltf", "meshes[0].primitives"},
    {"wrongTypes/badExtension.gltf", "extensions.KHR_texture_transform"},
    {"wrongTypes/badNumber.gltf", "materials[0].normalTexture"},
    {"wrongTypes/badObject.gltf", "materials[0].pbrMetallicRoughness"},
    {"wrongTypes/badString.gltf", ".name"},
    {"wrongTypes/badUint.gltf", "baseColorTexture.index"},
    {"SchemaFailures/sceneWrongType.gltf", "field 'scene'"},
    {"issue_3269/texcoord_crash.gltf", "TEXCOORD_0"},  // its material samples set 0; the primitive has only TEXCOORD_1
};

}  // namespace tbdr::input_validation
