#pragma once
// Node animation of a glTF scene (glTF 2.0, section 3.11 "Animations"): keyframed translation,
// rotation and scale of nodes, with STEP, LINEAR (spherical linear for rotations) or CUBICSPLINE
// interpolation. A sequence of frames poses the scene at each frame's time (the trace's `pose`
// line, docs/sequences.md): every instance's world matrix is its node's at that time.
// Morph-target weights and skins are not animated (the loader warns).
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace tbdr {

struct Scene;

/// A node's local transform: translation, rotation, scale (T x R x S), or a matrix (which no
/// channel may animate: glTF 2.0 requires TRS for animated nodes).
struct NodeTransform {
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 scale{1.0f};
  bool has_matrix = false;
  glm::mat4 matrix{1.0f};
  glm::mat4 local() const;
};

/// A node of the scene's hierarchy, as the animation needs it.
struct SceneNode {
  int parent = -1;      ///< index into SceneAnimation::nodes, -1 for a root
  NodeTransform rest;   ///< its transform in the file
};

/// Which property a channel animates.
enum class AnimationPath : std::uint8_t { Translation, Rotation, Scale };
/// How a channel's value moves between keys.
enum class AnimationInterpolation : std::uint8_t { Step, Linear, CubicSpline };

/// One animated property of one node.
struct AnimationChannel {
  std::uint32_t node = 0;  ///< index into SceneAnimation::nodes
  AnimationPath path = AnimationPath::Translation;
  AnimationInterpolation interpolation = AnimationInterpolation::Linear;
  std::vector<float> times;       ///< key times in seconds, non-decreasing
  /// Per key: the value (xyz, or a quaternion as x, y, z, w); CUBICSPLINE keys hold three:
  /// in-tangent, value, out-tangent.
  std::vector<glm::vec4> values;
};

/// One glTF animation.
struct Animation {
  std::string name;
  std::vector<AnimationChannel> channels;
  float duration_s = 0.0f;  ///< the last key time of any channel
};

/// The node hierarchy and animations of a scene (empty for the atrium and a glTF without any).
struct SceneAnimation {
  std::vector<SceneNode> nodes;
  std::vector<int> instance_node;  ///< per Scene::instances: the node that places it
  std::vector<Animation> animations;
};

/// The value of `channel` at `seconds` (before the first key: the first; after the last: the last).
glm::vec4 sample_channel(const AnimationChannel& channel, float seconds);

/// Poses `scene` at `seconds` of its animation `index`: every instance's world matrix becomes its
/// node's (the animated channels over the rest transforms, parents first), and the bounds follow.
/// Throws std::out_of_range when the scene has no animation `index`.
void pose_scene(Scene& scene, std::size_t index, double seconds);

}  // namespace tbdr
