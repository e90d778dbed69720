#include "scene/animation.hpp"

#include <algorithm>
#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/scene.hpp"

namespace tbdr {

glm::mat4 NodeTransform::local() const {
  if (has_matrix) return matrix;
  return glm::translate(glm::mat4(1.0f), translation) * glm::mat4_cast(rotation) * glm::scale(glm::mat4(1.0f), scale);
}

namespace {

glm::quat as_quat(const glm::vec4& v) { return glm::quat(v.w, v.x, v.y, v.z); }
glm::vec4 as_vec4(const glm::quat& q) { return glm::vec4(q.x, q.y, q.z, q.w); }

}  // namespace

glm::vec4 sample_channel(const AnimationChannel& c, float seconds) {
  const std::size_t keys = c.times.size();
  const bool cubic = c.interpolation == AnimationInterpolation::CubicSpline;
  auto value = [&](std::size_t k) { return c.values[cubic ? 3 * k + 1 : k]; };
  if (keys == 0) throw std::logic_error("sample_channel: a channel without keys");
  if (!(seconds > c.times.front())) return value(0);
  if (!(seconds < c.times.back())) return value(keys - 1);
  // The key interval [k, k + 1) holding `seconds`.
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(c.times.begin(), c.times.end(), seconds) - c.times.begin()) - 1;
  const float dt = c.times[k + 1] - c.times[k];
  const float u = dt > 0.0f ? (seconds - c.times[k]) / dt : 0.0f;
  const bool rotation = c.path == AnimationPath::Rotation;
  glm::vec4 v;
  switch (c.interpolation) {
    case AnimationInterpolation::Step:
      return value(k);
    case AnimationInterpolation::Linear:
      if (rotation) return as_vec4(glm::normalize(glm::slerp(as_quat(value(k)), as_quat(value(k + 1)), u)));
      return value(k) + (value(k + 1) - value(k)) * u;
    case AnimationInterpolation::CubicSpline: {
      // glTF 2.0 Appendix C: Hermite spline with the keys' out- and in-tangents scaled by dt.
      const float u2 = u * u, u3 = u2 * u;
      const glm::vec4 b = c.values[3 * k + 2] * dt;        // out-tangent of key k
      const glm::vec4 a = c.values[3 * (k + 1)] * dt;      // in-tangent of key k + 1
      v = (2 * u3 - 3 * u2 + 1) * value(k) + (u3 - 2 * u2 + u) * b + (-2 * u3 + 3 * u2) * value(k + 1) + (u3 - u2) * a;
      if (rotation) v = as_vec4(glm::normalize(as_quat(v)));
      return v;
    }
  }
  return value(k);
}

void pose_scene(Scene& scene, std::size_t index, double seconds) {
  SceneAnimation& anim = scene.animation;
  if (index >= anim.animations.size()) {
    throw std::out_of_range("scene " + scene.source + " has " + std::to_string(anim.animations.size()) +
                            " animation(s); there is no animation " + std::to_string(index));
  }
  std::vector<NodeTransform> pose(anim.nodes.size());
  for (std::size_t n = 0; n < anim.nodes.size(); ++n) pose[n] = anim.nodes[n].rest;
  for (const AnimationChannel& c : anim.animations[index].channels) {
    const glm::vec4 v = sample_channel(c, static_cast<float>(seconds));
    NodeTransform& t = pose.at(c.node);
    switch (c.path) {
      case AnimationPath::Translation: t.translation = glm::vec3(v); break;
      case AnimationPath::Rotation: t.rotation = glm::normalize(as_quat(v)); break;
      case AnimationPath::Scale: t.scale = glm::vec3(v); break;
    }
  }
  // World matrices, parents first (a node's parent may come after it in the list).
  std::vector<glm::mat4> world(anim.nodes.size());
  std::vector<std::uint8_t> done(anim.nodes.size(), 0);
  std::vector<std::size_t> chain;
  for (std::size_t n = 0; n < anim.nodes.size(); ++n) {
    for (std::size_t at = n; !done[at];) {
      chain.push_back(at);
      const int p = anim.nodes[at].parent;
      if (p < 0 || done[static_cast<std::size_t>(p)]) break;
      at = static_cast<std::size_t>(p);
    }
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      const int p = anim.nodes[*it].parent;
      world[*it] = (p < 0 ? glm::mat4(1.0f) : world[static_cast<std::size_t>(p)]) * pose[*it].local();
      done[*it] = 1;
    }
    chain.clear();
  }
  for (std::size_t i = 0; i < scene.instances.size() && i < anim.instance_node.size(); ++i) {
    scene.instances[i].world = world.at(static_cast<std::size_t>(anim.instance_node[i]));
  }
  update_bounds(scene);
}

}  // namespace tbdr
