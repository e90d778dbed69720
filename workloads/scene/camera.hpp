#pragma once
// Cameras: a pinhole camera with a right-handed view and an OpenGL-style projection
// (clip-space z in [-w, w]); named viewpoints for the built-in atrium; a framing default for glTF.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "scene/scene.hpp"

namespace tbdr {

/// A perspective camera as an application would set it up.
struct Camera {
  glm::vec3 eye{0.0f, 0.0f, 5.0f};
  glm::vec3 target{0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float fov_y_deg = 60.0f;   ///< vertical field of view, degrees
  float near_plane = 0.1f;   ///< world units
  float far_plane = 100.0f;  ///< world units

  glm::mat4 view() const;                       ///< world to eye (glm::lookAt)
  glm::mat4 projection(float aspect) const;     ///< eye to clip (glm::perspective, GL depth range)
};

/// Named viewpoints of the atrium ("entrance", "gallery", "top", ...), in the order listed.
std::vector<std::string> atrium_viewpoint_names();
/// The atrium camera of that name; throws InputError listing the valid names otherwise.
Camera atrium_viewpoint(const std::string& name, const Scene& atrium);
/// A camera that frames the scene's bounds from the front (+z looking to -z), near/far from bounds.
Camera framing_camera(const Scene& scene);

/// How the camera of a frame sequence moves from its first frame's viewpoint.
enum class CameraPath : std::uint8_t {
  Static,      ///< the same camera every frame (what transaction elimination and warm caches are measured on)
  Orbit,       ///< the eye turns about the vertical axis through the target, kOrbitDegreesPerFrame per frame
  Flythrough,  ///< eye and target move together along the view direction, kFlythroughStepFraction of
               ///< the eye-target distance per frame (a walk forward through the scene)
};
/// Degrees the orbit turns per frame: 360 degrees in 6 s at 60 frames per second.
inline constexpr float kOrbitDegreesPerFrame = 1.0f;
/// Fraction of the first frame's eye-target distance the flythrough moves per frame: after 100
/// frames the eye stands where the target was.
inline constexpr float kFlythroughStepFraction = 0.01f;
/// The path's name as `tbdrsim trace --camera-path` takes it ("static", "orbit", "flythrough").
const char* to_string(CameraPath p);
/// The path of that name; throws InputError listing the names otherwise.
CameraPath parse_camera_path(const std::string& name);
/// The path of that name, or none (`tbdrsim trace --camera-path` then takes it as a file).
std::optional<CameraPath> camera_path_named(const std::string& name);
/// Reads a camera path file (docs/sequences.md): after the header `tbdrsim-camera-path 1`, the
/// camera of frame k on its k-th line, `eye_x eye_y eye_z target_x target_y target_z
/// [fov_y_deg]`; up, near and far (and the field of view where a line gives none) are `first`'s.
/// InputError naming file:line for a malformed number, a coordinate beyond 1e9, an eye on its
/// target, a view along `up`, a field of view outside [0.01, 179] degrees, or no camera at all.
std::vector<Camera> read_camera_path_file(const std::string& path, const Camera& first);
/// The camera of frame `frame` (0: `first`) of a sequence along `path`.
Camera camera_on_path(const Camera& first, CameraPath path, int frame);

}  // namespace tbdr
