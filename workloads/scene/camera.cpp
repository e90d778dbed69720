#include "scene/camera.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "kernel/errors.hpp"
#include "scene/number_file.hpp"
#include "scene/atrium.hpp"

namespace tbdr {

glm::mat4 Camera::view() const { return glm::lookAt(eye, target, up); }

glm::mat4 Camera::projection(float aspect) const {
  // glm's default (no GLM_FORCE_DEPTH_ZERO_TO_ONE) is the OpenGL clip range z in [-w, w].
  return glm::perspective(glm::radians(fov_y_deg), aspect, near_plane, far_plane);
}

namespace {

/// One named atrium viewpoint: eye and target in the atrium's meters (see workloads/scene/atrium.hpp).
struct AtriumView {
  const char* name;
  glm::vec3 eye;
  glm::vec3 target;
  float fov_y_deg;
};

std::vector<AtriumView> atrium_views() {
  const AtriumLayout L = atrium_layout();
  const float eye_h = 1.7f;  // standing eye height, meters
  // The street view: at 60.5 m from the facade a 15 degree view spans 60.5 tan(7.5 deg) = +-7.96 m
  // vertically (y 0.04 .. 15.96 at eye height 8) and +-14.2 m horizontally at 16:9: only facade,
  // which spans 0 .. 16.3 m in height and 39 m in length.
  const float street_eye_h = 8.0f, street_distance_m = 60.0f;
  return {
      // At the west end of the courtyard, eye height, looking east along its length: both
      // colonnades recede in rows, banners and plants overlap the arcades.
      {"entrance", {-L.court_half_x + 1.0f, eye_h, -1.2f}, {L.court_half_x, 3.2f, 0.6f}, 60.0f},
      // On the upper gallery (north side), looking diagonally across the courtyard at the far arcades.
      {"gallery",
       {-L.court_half_x + 2.0f, L.storey1_height + eye_h, L.court_half_z + 0.5f * L.aisle_depth},
       {L.court_half_x * 0.5f, L.storey1_height * 0.6f, -L.court_half_z},
       60.0f},
      // High above the south-west corner looking down into the courtyard.
      {"top", {-L.court_half_x * 0.3f, L.roof_height * 2.0f, -L.outer_half_z * 1.3f}, {0.0f, 2.0f, 0.0f}, 60.0f},
      // Inside the ground-floor south aisle, looking east down the row of columns.
      {"aisle", {-L.court_half_x + 0.5f, eye_h, -L.court_half_z - 0.5f * L.aisle_depth}, {L.court_half_x, 2.0f, -L.court_half_z + 1.0f}, 60.0f},
      // In the courtyard looking up at the banners hanging in front of the north upper arcade.
      {"banners", {2.0f, eye_h, -L.court_half_z + 1.5f}, {0.0f, L.storey1_height, L.court_half_z}, 60.0f},
      // Outside, 60 m in front of the south facade, a 15 degree telephoto at mid height: the
      // facade fills the frame and the whole interior behind it (both arcades, glass, banners,
      // plants) is submitted and rasterised, as by an engine without occlusion culling; the
      // atrium's deepest view (bench/hsr_anchor.sh).
      {"street", {0.0f, street_eye_h, -L.outer_half_z - street_distance_m}, {0.0f, street_eye_h, 0.0f}, 15.0f},
  };
}

}  // namespace

std::vector<std::string> atrium_viewpoint_names() {
  std::vector<std::string> names;
  for (const AtriumView& v : atrium_views()) names.emplace_back(v.name);
  return names;
}

Camera atrium_viewpoint(const std::string& name, const Scene& atrium) {
  for (const AtriumView& v : atrium_views()) {
    if (name != v.name) continue;
    Camera cam;
    cam.eye = v.eye;
    cam.target = v.target;
    cam.up = glm::vec3(0.0f, 1.0f, 0.0f);
    cam.fov_y_deg = v.fov_y_deg;
    cam.near_plane = 0.1f;
    // Far: the farthest bounds corner from the eye, so nothing in the scene is clipped away.
    const Bounds& b = atrium.bounds;
    float far_m = 0.0f;
    for (int i = 0; i < 8; ++i) {
      const glm::vec3 c((i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y, (i & 4) ? b.max.z : b.min.z);
      far_m = std::max(far_m, glm::length(c - v.eye));
    }
    cam.far_plane = std::max(far_m * 1.01f, 1.0f);
    return cam;
  }
  std::string valid;
  for (const std::string& n : atrium_viewpoint_names()) valid += (valid.empty() ? "" : ", ") + n;
  throw InputError("viewpoint '" + name + "'", "unknown atrium viewpoint; valid: " + valid);
}

Camera framing_camera(const Scene& scene) {
  Camera cam;
  const glm::vec3 center = scene.bounds.center();
  float radius = 0.5f * glm::length(scene.bounds.extent());
  if (!(radius > 0.0f) || !std::isfinite(radius)) radius = 1.0f;
  cam.fov_y_deg = 60.0f;
  // Distance at which the bounding sphere fits the vertical field of view, with 5% margin.
  const float dist = 1.05f * radius / std::sin(glm::radians(cam.fov_y_deg) * 0.5f);
  cam.eye = center + glm::vec3(0.0f, 0.0f, dist);
  cam.target = center;
  cam.up = glm::vec3(0.0f, 1.0f, 0.0f);
  cam.near_plane = std::max(dist - radius, radius * 1e-3f) * 0.9f;
  cam.far_plane = (dist + radius) * 1.1f;
  return cam;
}

const char* to_string(CameraPath p) {
  switch (p) {
    case CameraPath::Static: return "static";
    case CameraPath::Orbit: return "orbit";
    case CameraPath::Flythrough: return "flythrough";
  }
  return "?";
}

std::optional<CameraPath> camera_path_named(const std::string& name) {
  for (CameraPath p : {CameraPath::Static, CameraPath::Orbit, CameraPath::Flythrough}) {
    if (name == to_string(p)) return p;
  }
  return std::nullopt;
}

CameraPath parse_camera_path(const std::string& name) {
  if (const auto p = camera_path_named(name)) return *p;
  throw InputError("--camera-path " + name, "unknown camera path; valid: static, orbit, flythrough");
}

std::vector<Camera> read_camera_path_file(const std::string& path, const Camera& first) {
  // The trace reader's bounds (docs/limits.md): coordinates within 1e9, a field of view in
  // [0.01, 179] degrees, a view at least asin(1e-3) (0.06 degrees) away from `up`.
  constexpr float kMaxCoordinate = 1e9f, kMinFov = 0.01f, kMaxFov = 179.0f, kMinUpSine = 1e-3f;
  NumberFile file(path, "tbdrsim-camera-path", 1, "camera path file");
  static const char* names[] = {"eye_x", "eye_y", "eye_z", "target_x", "target_y", "target_z", "fov_y_deg"};
  std::vector<Camera> cameras;
  std::vector<std::string> words;
  while (file.next(words)) {
    if (words.size() != 6 && words.size() != 7) {
      file.fail("a camera needs 6 numbers (eye, target) and optionally a 7th (fov_y_deg), got " + std::to_string(words.size()));
    }
    float v[7] = {};
    for (std::size_t k = 0; k < words.size(); ++k) {
      v[k] = file.number(words[k], names[k]);
      if (k < 6 && std::abs(v[k]) > kMaxCoordinate) file.fail(std::string(names[k]) + " '" + words[k] + "' is beyond +-1e+09");
    }
    Camera c = first;
    c.eye = {v[0], v[1], v[2]};
    c.target = {v[3], v[4], v[5]};
    if (words.size() == 7) {
      if (v[6] < kMinFov || v[6] > kMaxFov) file.fail("fov_y_deg '" + words[6] + "' is outside [0.01, 179]");
      c.fov_y_deg = v[6];
    }
    const glm::vec3 view = c.target - c.eye;
    if (!(glm::length(view) > 0.0f)) file.fail("the eye is on the target: no view direction");
    const float sine = glm::length(glm::cross(glm::normalize(view), glm::normalize(c.up)));
    if (sine < kMinUpSine) file.fail("the view direction is along the camera's up vector (no camera basis)");
    cameras.push_back(c);
  }
  if (cameras.empty()) file.fail("no camera: a camera path file holds one camera per frame");
  return cameras;
}

Camera camera_on_path(const Camera& first, CameraPath path, int frame) {
  Camera c = first;
  switch (path) {
    case CameraPath::Static:
      break;
    case CameraPath::Orbit: {
      // About the world's vertical axis (y) through the target: the eye keeps its height and distance.
      const float angle = glm::radians(kOrbitDegreesPerFrame * static_cast<float>(frame));
      const glm::vec3 offset = first.eye - first.target;
      const float cs = std::cos(angle), sn = std::sin(angle);
      c.eye = first.target + glm::vec3(cs * offset.x + sn * offset.z, offset.y, -sn * offset.x + cs * offset.z);
      break;
    }
    case CameraPath::Flythrough: {
      const glm::vec3 step = (first.target - first.eye) * (kFlythroughStepFraction * static_cast<float>(frame));
      c.eye = first.eye + step;
      c.target = first.target + step;
      break;
    }
  }
  return c;
}

}  // namespace tbdr
