#pragma once
// Cameras: a pinhole camera with a right-handed view and an OpenGL-style projection
// (clip-space z in [-w, w]); named viewpoints for the built-in atrium; a framing default for glTF.
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

}  // namespace tbdr
