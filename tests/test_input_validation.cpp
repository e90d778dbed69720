// Hostile input (issue 16): every input the reader accepted but should refuse is refused with
// file:line (or the field), the offending token and what was expected, before any work; every
// declared limit (docs/limits.md) is enforced; a UTF-8 byte-order mark is accepted.
#include <gtest/gtest.h>

#include <unistd.h>

#include <climits>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "app/cli.hpp"
#include "app/sweep_spec.hpp"
#include "kernel/errors.hpp"
#include "kernel/params.hpp"
#include "models/hw_config.hpp"
#include "scene/atrium.hpp"
#include "scene/gltf_loader.hpp"
#include "scratch_dir.hpp"
#include "trace/trace.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;
using testing_scratch::scratch_dir;
const testing_scratch::ScratchCleanup cleanup{"input_validation"};

fs::path dir_for(const std::string& name) { return scratch_dir("input_validation", name); }

void write_file(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

// A small valid trace on the atrium at detail 1: `decl` is spliced in after the camera (lights,
// buffers) and `body` after the declarations (passes, dispatches).
std::string trace_text(const std::string& camera, const std::string& decl, const std::string& body) {
  return "tbdrsim-trace 2\n"                                                                   // 1
         "scene atrium detail=1\n"                                                             // 2
         "frame width=64 height=64 samples=1\n"                                                // 3
         + camera + "\n" +                                                                     // 4
         decl +
         "shader s alu_ops=4 tex_fetches=0 varyings=4 light_alu_ops=0 light_source=none color_outputs=1\n"
         "pipeline p shader=s depth_test=yes depth_write=yes blend=off cull=back\n" + body;
}
const std::string kCamera = "camera eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100";
const std::string kPass =
    "pass main\n"
    "  attachment color format=rgba8 samples=1 load=clear store=store usage=color\n"
    "  attachment depth format=d24s8 samples=1 load=clear store=dont_care usage=depth transient=no\n"
    "  draw scene pipeline=p\n"
    "end\n";

// Parsing `text` throws an InputError at "t.trace:line" whose message holds every `tokens`.
void expect_refused(const std::string& text, int line, std::initializer_list<std::string> tokens) {
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

Trace parse(const std::string& text) {
  std::istringstream in(text);
  return parse_trace(in, "t.trace");
}

struct CliResult {
  int code;
  std::string out, err;
};
CliResult run_cli(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  const int code = cli_main(args, out, err);
  return {code, out.str(), err.str()};
}

// ---- the trace: references and numeric ranges ---------------------------------------------------

TEST(InputValidation, BaseTraceIsAccepted) {
  // The refusals below differ from this accepted trace by one line each.
  const Trace t = parse(trace_text(kCamera, "", kPass));
  EXPECT_EQ(t.commands.size(), 1u);
}

TEST(InputValidation, DrawOfASubMeshOrMaterialTheSceneLacksIsRefusedBeforeWork) {
  const std::string body_sub = "pass main\n"
                               "  attachment color format=rgba8 samples=1 load=clear store=store usage=color\n"
                               "  attachment depth format=d24s8 samples=1 load=clear store=dont_care usage=depth\n"
                               "  draw scene pipeline=p submesh=no_such_mesh\n"  // line 10
                               "end\n";
  const Trace t = parse(trace_text(kCamera, "", body_sub));
  const Scene atrium = make_atrium(1);
  try {
    check_scene_references(t, atrium, "t.trace");
    ADD_FAILURE() << "a draw of a missing sub-mesh was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "t.trace:10");
    EXPECT_NE(std::string(e.what()).find("submesh='no_such_mesh'"), std::string::npos) << e.what();
  }
  std::string body_mat = body_sub;
  body_mat.replace(body_mat.find("submesh=no_such_mesh"), 20, "material=no_such_mat");
  EXPECT_THROW(check_scene_references(parse(trace_text(kCamera, "", body_mat)), atrium, "t.trace"), InputError);
  // A name the atrium has passes.
  body_mat.replace(body_mat.find("material=no_such_mat"), 20, "material=\"" + atrium.materials.front().name + "\"");
  EXPECT_NO_THROW(check_scene_references(parse(trace_text(kCamera, "", body_mat)), atrium, "t.trace"));

  // Through the command line: exit 2 naming file:line, and no database written.
  const fs::path dir = dir_for("missing_submesh");
  write_file(dir / "t.trace", trace_text(kCamera, "", body_sub));
  const auto r = run_cli({"run", "--trace", (dir / "t.trace").string(), "--db", (dir / "r.db").string(), "--quiet"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("t.trace:10"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "r.db"));
}

TEST(InputValidation, PlsOfTenThousandBytesPerPixelIsRefused) {
  // 625 rgba32f variables x 16 bytes = 10,000 bytes per pixel, far above pls.max_pls_bytes_per_pixel.
  std::string pls;
  for (int i = 0; i < 625; ++i) pls += "  pls v" + std::to_string(i) + " format=rgba32f\n";
  const std::string body = "pass main\n"  // line 7
                           "  attachment color format=rgba8 samples=1 load=clear store=store usage=color\n" +
                           pls + "  draw fullscreen pipeline=q\nend\n";
  const std::string decl = "shader t alu_ops=4 tex_fetches=0 varyings=2 light_alu_ops=0 light_source=none color_outputs=0 "
                           "pls=read_write\npipeline q shader=t depth_test=no depth_write=no blend=off cull=none\n";
  const fs::path dir = dir_for("pls");
  write_file(dir / "t.trace", trace_text(kCamera, decl, body));
  const auto r = run_cli({"run", "--trace", (dir / "t.trace").string(), "--db", (dir / "r.db").string(), "--quiet"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("t.trace:9"), std::string::npos) << r.err;  // the pass line (2 declarations more)
  EXPECT_NE(r.err.find("10000 bytes"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("pls.max_pls_bytes_per_pixel"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "r.db"));
}

TEST(InputValidation, CameraUpParallelToTheViewIsRefused) {
  expect_refused(trace_text("camera eye=0,0,0 target=0,5,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100", "", kPass), 4,
                 {"up '0,1,0'", "parallel"});
  // Anti-parallel too, and 0.01 degrees off (sine 1.7e-4 < 1e-3).
  expect_refused(trace_text("camera eye=0,0,0 target=0,5,0 up=0,-1,0 fov_y_deg=60 near=0.1 far=100", "", kPass), 4,
                 {"parallel"});
  expect_refused(trace_text("camera eye=0,0,0 target=0,5,0 up=0.00017,1,0 fov_y_deg=60 near=0.1 far=100", "", kPass), 4,
                 {"parallel"});
  // 0.1 degrees off (sine 1.7e-3) is a usable basis.
  EXPECT_NO_THROW(parse(trace_text("camera eye=0,0,0 target=0,5,0 up=0.0017,1,0 fov_y_deg=60 near=0.1 far=100", "", kPass)));
}

TEST(InputValidation, DegenerateProjectionsAreRefused) {
  expect_refused(trace_text("camera eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=1e-30 near=0.1 far=100", "", kPass), 4,
                 {"fov_y_deg '1e-30'", "[0.01, 179]"});
  expect_refused(trace_text("camera eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=179.5 near=0.1 far=100", "", kPass), 4,
                 {"fov_y_deg '179.5'"});
  expect_refused(trace_text("camera eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=60 near=1e-30 far=1e38", "", kPass), 4,
                 {"near '1e-30'"});
  expect_refused(trace_text("camera eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=60 near=0.1 far=1e38", "", kPass), 4,
                 {"far '1e38'"});
  // far/near = 1e8 > 2^24 = 1.68e7, each within its own range.
  expect_refused(trace_text("camera eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=60 near=1e-3 far=1e5", "", kPass), 4,
                 {"far/near", "16777216"});
  expect_refused(trace_text("camera eye=0,2,1e20 target=0,2,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100", "", kPass), 4,
                 {"eye=0,2,1e20"});
}

TEST(InputValidation, LightBufferSmallerThanTheLightsIsRefused) {
  // 104 lights need 104 x 48 = 4992 bytes; 192 holds 4.
  std::string lights;
  for (int i = 0; i < 104; ++i) lights += "light point position=0,1,0 radius=1 color=1,1,1 intensity=1\n";
  const std::string decl = lights + "buffer lights bytes=192 traffic=light_data content=lights upload=yes\n";  // line 109
  expect_refused(trace_text(kCamera, decl, kPass), 109, {"bytes=192", "104 lights need 4992"});
  std::string ok = decl;
  ok.replace(ok.find("bytes=192"), 9, "bytes=4992");
  EXPECT_NO_THROW(parse(trace_text(kCamera, ok, kPass)));
}

TEST(InputValidation, DispatchSizesBeyondVulkanLimitsAreRefused) {
  const std::string decl = "buffer out bytes=64 traffic=other content=other\n";
  expect_refused(trace_text(kCamera, decl,
                            "dispatch tile_light_cull groups=4294967295,4294967295,4294967295 group_size=16,16,1 writes=out\n"),
                 8, {"groups=4294967295,4294967295,4294967295", "65535"});
  expect_refused(trace_text(kCamera, decl, "dispatch tile_light_cull groups=1,1,1 group_size=64,64,1 writes=out\n"), 8,
                 {"group_size=64,64,1", "4096 invocations", "1024"});
}

TEST(InputValidation, AtriumDetailOutsideOneToFiveIsRefused) {
  std::string t = trace_text(kCamera, "", kPass);
  for (const char* bad : {"detail=0", "detail=6", "detail=16"}) {
    std::string text = t;
    text.replace(text.find("detail=1"), 8, bad);
    expect_refused(text, 2, {"detail"});
  }
}

// ---- the trace: declared limits ------------------------------------------------------------------

TEST(InputValidation, HugeBufferIsRefusedNotAllocated) {
  // 1 TiB (2^40) > kMaxBufferBytes = 16 GiB; an upload buffer above 256 MiB is refused too.
  expect_refused(trace_text(kCamera, "buffer big bytes=1099511627776 traffic=other content=other upload=yes\n", kPass), 5,
                 {"1099511627776", "0..17179869184"});
  expect_refused(trace_text(kCamera, "buffer big bytes=268435457 traffic=other content=other upload=yes\n", kPass), 5,
                 {"upload=yes", "268435456"});
  EXPECT_NO_THROW(parse(trace_text(kCamera, "buffer big bytes=17179869184 traffic=other content=other\n", kPass)));
}

TEST(InputValidation, FrameLargerThanTheSampleBudgetIsRefused) {
  std::string t = trace_text(kCamera, "", kPass);
  // 16384 x 16384 x 2 = 2^29 samples > 2^28; at one sample it is exactly the budget.
  std::string two = t;
  two.replace(two.find("frame width=64 height=64 samples=1"), 34, "frame width=16384 height=16384 samples=2");
  expect_refused(two, 3, {"536870912 samples", "268435456"});
  std::string side = t;
  side.replace(side.find("width=64"), 8, "width=16385");
  expect_refused(side, 3, {"16385", "0..16384"});
}

TEST(InputValidation, MoreCommandsThanTheLimitAreRefusedAsTheyAreRead) {
  // 65,537 barriers: one past kMaxTraceCommands; the error names the first line beyond it.
  std::string body;
  for (std::uint64_t i = 0; i <= kMaxTraceCommands; ++i) body += "barrier resources=all\n";
  expect_refused(trace_text(kCamera, "", body), 7 + static_cast<int>(kMaxTraceCommands), {"65536 passes, dispatches and barriers"});
}

TEST(InputValidation, TraceFileLargerThanTheLimitIsRefusedBeforeReading) {
  const fs::path dir = dir_for("big_trace");
  const fs::path p = dir / "big.trace";
  write_file(p, trace_text(kCamera, "", kPass));
  fs::resize_file(p, kMaxTraceBytes + 1);  // sparse: no disk, and refused by its size alone
  try {
    read_trace(p.string());
    ADD_FAILURE() << "a trace of kMaxTraceBytes + 1 was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("268435457 bytes"), std::string::npos) << e.what();
  }
}

TEST(InputValidation, PathsLongerThanTheFileSystemAllowsAreInputErrors) {
  const long name_max = ::pathconf(fs::temp_directory_path().c_str(), _PC_NAME_MAX);
  ASSERT_GT(name_max, 0);
  const std::string long_name = (fs::temp_directory_path() / std::string(static_cast<std::size_t>(name_max) + 1, 'a')).string() + ".trace";
  EXPECT_THROW(read_trace(long_name), InputError);
  std::string long_path = fs::temp_directory_path().string();
  while (long_path.size() < PATH_MAX + 10) long_path += "/abc";
  EXPECT_THROW(read_trace(long_path), InputError);
  const auto r = run_cli({"run", "--trace", long_name, "--db", (dir_for("long") / "r.db").string(), "--quiet"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("_PC_NAME_MAX"), std::string::npos) << r.err;
  const auto c = run_cli({"params", "--config", long_path});
  EXPECT_EQ(c.code, 2) << c.err;
  EXPECT_NE(c.err.find("_PC_PATH_MAX"), std::string::npos) << c.err;
}

// ---- byte-order marks ----------------------------------------------------------------------------

const std::string kBom = "\xEF\xBB\xBF";

TEST(InputValidation, Utf8ByteOrderMarkIsAcceptedInTraceConfigAndSweepFiles) {
  const Trace t = parse(kBom + trace_text(kCamera, "", kPass));
  EXPECT_EQ(t.version, 2);

  const fs::path dir = dir_for("bom");
  write_file(dir / "c.ini", kBom + "[isp]\ntag_buffers = 4\n");
  const ParamTable& table = hw_params().table();
  const ResolvedParams p = table.resolve({(dir / "c.ini").string()}, {});
  EXPECT_EQ(format_param_value(p.values[static_cast<std::size_t>(table.find("isp.tag_buffers"))]), "4");

  write_file(dir / "t.trace", "x");
  write_file(dir / "s.ini", kBom + "[sweep]\ntrace = t.trace\n[vary]\nisp.tag_buffers = 1, 2\n");
  const SweepSpec s = parse_sweep_file((dir / "s.ini").string());
  EXPECT_EQ(expand_sweep(s).size(), 2u);
}

// ---- sweeps --------------------------------------------------------------------------------------

/// The first real-valued hardware parameter whose range holds 1.
std::string a_real_parameter() {
  for (const auto& d : hw_params().table().decls())
    if (d.type == ParamType::Real && d.min <= 1.0 && d.max >= 1.0) return d.key;
  return {};
}

TEST(InputValidation, SweepValueWrittenTwiceInTwoSpellingsIsRefused) {
  const std::string key = a_real_parameter();
  ASSERT_FALSE(key.empty());
  const fs::path dir = dir_for("sweep_twice");
  write_file(dir / "t.trace", "x");
  write_file(dir / "s.ini", "[sweep]\ntrace = t.trace\n[vary]\n" + key + " = 1.0, 1\n");  // line 4
  try {
    parse_sweep_file((dir / "s.ini").string());
    ADD_FAILURE() << "'1.0, 1' accepted for " << key;
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), (dir / "s.ini").string() + ":4");
    EXPECT_NE(std::string(e.what()).find("'1' and '1.0' are the same value"), std::string::npos) << e.what();
  }
}

TEST(InputValidation, SweepOfMoreThanAMillionPointsIsRefusedBeforeExpanding) {
  // Integer parameters whose range holds 1..1000.
  std::vector<std::string> keys;
  for (const auto& d : hw_params().table().decls())
    if (d.type == ParamType::Int && d.min <= 1 && d.max >= 1000) keys.push_back(d.key);
  ASSERT_GE(keys.size(), 2u);
  const fs::path dir = dir_for("sweep_big");
  write_file(dir / "t.trace", "x");
  // 1000 repetitions x 1000 x 1000 values = 10^9 points (std::bad_alloc before): refused at the file.
  write_file(dir / "s.ini", "[sweep]\ntrace = t.trace\nrepetitions = 1000\n[vary]\n" + keys[0] + " = 1..1000\n" + keys[1] +
                                " = 1..1000\n");
  try {
    parse_sweep_file((dir / "s.ini").string());
    ADD_FAILURE() << "10^9 points accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), (dir / "s.ini").string());
    EXPECT_NE(std::string(e.what()).find("more than 1000000 points"), std::string::npos) << e.what();
  }
  // 1 x 1000 x 1000 = 10^6 points is exactly the limit: accepted (expanding is left to a sweep).
  write_file(dir / "s.ini", "[sweep]\ntrace = t.trace\n[vary]\n" + keys[0] + " = 1..1000\n" + keys[1] + " = 1..1000\n");
  EXPECT_NO_THROW(parse_sweep_file((dir / "s.ini").string()));
}

// ---- glTF ----------------------------------------------------------------------------------------

// A one-triangle glTF with its buffer in a data URI; `patch` edits its JSON text.
std::string tiny_gltf(const std::string& extra_top = "", const std::string& primitive_extra = "",
                      const std::string& attributes = "\"POSITION\": 0") {
  // 3 x VEC3 float positions (0,0,0) (1,0,0) (0,1,0), base64 of 36 bytes.
  const std::string positions = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";
  return "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}], \"nodes\": [{\"mesh\": 0}],"
         "\"meshes\": [{\"primitives\": [{\"attributes\": {" + attributes + "}" + primitive_extra + "}]}],"
         "\"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\","
         "\"max\": [1, 1, 0], \"min\": [0, 0, 0]}],"
         "\"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}],"
         "\"buffers\": [{\"byteLength\": 36, \"uri\": \"data:application/octet-stream;base64," + positions + "\"}]" +
         extra_top + "}";
}

// Loading `json` throws an InputError naming the file and containing `field`.
void expect_gltf_refused(const std::string& json, const std::string& field) {
  const fs::path dir = dir_for("gltf");
  const fs::path p = dir / "x.gltf";
  write_file(p, json);
  try {
    load_gltf(p.string());
    ADD_FAILURE() << "accepted: " << json;
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), p.string()) << e.what();
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << "'" << field << "' not in " << e.what();
  }
}

TEST(InputValidation, GltfBaseFileLoads) {
  const fs::path p = dir_for("gltf_ok") / "ok.gltf";
  write_file(p, tiny_gltf());
  EXPECT_EQ(load_gltf(p.string()).triangle_count(), 1u);
}

TEST(InputValidation, GltfWrongJsonTypesAreRefusedNamingTheField) {
  std::string s = tiny_gltf();
  auto with = [](std::string text, const std::string& from, const std::string& to) {
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  expect_gltf_refused(with(s, "\"scene\": 0", "\"scene\": \"hello\""), "field 'scene': expected a non-negative integer");
  expect_gltf_refused(with(s, "\"count\": 3", "\"count\": \"3\""), "field 'accessors[0].count'");
  expect_gltf_refused(with(s, "\"count\": 3", "\"count\": 3.5"), "field 'accessors[0].count'");
  expect_gltf_refused(with(s, "\"nodes\": [0]", "\"nodes\": [-1]"), "field 'scenes[0].nodes[0]'");
  expect_gltf_refused(with(s, "\"max\": [1, 1, 0]", "\"max\": [1, \"a\", 0]"), "field 'accessors[0].max[1]'");
  expect_gltf_refused(with(s, "{\"mesh\": 0}", "{\"mesh\": 0, \"name\": 42}"), "field 'nodes[0].name': expected a string");
  expect_gltf_refused(with(s, "\"asset\": {\"version\": \"2.0\"}", "\"asset\": {\"version\": 2}"), "field 'asset.version'");
  expect_gltf_refused(with(s, "\"asset\": {\"version\": \"2.0\"}, ", ""), "field 'asset': required");
  expect_gltf_refused(tiny_gltf("", "", "\"POSITION\": \"zero\""), "field 'meshes[0].primitives[0].attributes.POSITION'");
  expect_gltf_refused(tiny_gltf(", \"materials\": [{\"pbrMetallicRoughness\": 5}]"),
                      "field 'materials[0].pbrMetallicRoughness': expected an object");
  expect_gltf_refused(tiny_gltf(", \"materials\": [{\"normalTexture\": {\"index\": 0, \"scale\": \"big\"}}]"),
                      "field 'materials[0].normalTexture.scale': expected a number");
  expect_gltf_refused(tiny_gltf(", \"materials\": [{\"extensions\": {\"KHR_x\": \"Not an object\"}}]"),
                      "field 'materials[0].extensions.KHR_x'");
}

TEST(InputValidation, GltfTexturedMaterialOnAPrimitiveWithoutItsTexcoordSetIsRefused) {
  // A 1x1 RGBA PNG, base64.
  const std::string png = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg==";
  const std::string textured = ", \"materials\": [{\"pbrMetallicRoughness\": {\"baseColorTexture\": {\"index\": 0}}}],"
                               " \"textures\": [{\"source\": 0}], \"images\": [{\"uri\": \"data:image/png;base64," + png + "\"}]";
  // The same accessor as TEXCOORD_1 (VEC3 is the wrong type for uvs, but the set is missing first).
  expect_gltf_refused(tiny_gltf(textured, ", \"material\": 0", "\"POSITION\": 0, \"TEXCOORD_1\": 0"), "TEXCOORD_0");
}

/// Debian's assimp-testmodels: glTF files that are broken on purpose.
TEST(InputValidation, AssimpBrokenGltfCorpusIsRefused) {
  const fs::path root = "/usr/share/assimp/models/glTF2";
  if (!fs::is_directory(root / "wrongTypes")) GTEST_SKIP() << "assimp-testmodels not installed (apt install assimp-testmodels)";
  const std::pair<const char*, const char*> cases[] = {
      {"wrongTypes/badArray.gltf", "meshes[0].primitives"},
      {"wrongTypes/badExtension.gltf", "extensions.KHR_texture_transform"},
      {"wrongTypes/badNumber.gltf", "materials[0].normalTexture"},
      {"wrongTypes/badObject.gltf", "materials[0].pbrMetallicRoughness"},
      {"wrongTypes/badString.gltf", ".name"},
      {"wrongTypes/badUint.gltf", "baseColorTexture.index"},
      {"SchemaFailures/sceneWrongType.gltf", "field 'scene'"},
      {"issue_3269/texcoord_crash.gltf", "TEXCOORD_0"},  // its material samples set 0; the primitive has only TEXCOORD_1
  };
  for (const auto& [file, field] : cases) {
    const std::string p = (root / file).string();
    try {
      load_gltf(p);
      ADD_FAILURE() << p << " loaded";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), p) << e.what();
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << "'" << field << "' not in " << e.what();
    }
    const auto r = run_cli({"scene-info", p});
    EXPECT_EQ(r.code, 2) << p << ": " << r.err;
  }
}

}  // namespace
}  // namespace tbdr
