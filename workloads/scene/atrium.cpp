#include "scene/atrium.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "kernel/errors.hpp"
#include "kernel/hash.hpp"
#include "kernel/random.hpp"

namespace tbdr {

namespace {

constexpr float pi = std::numbers::pi_v<float>;

/// Integer hash to [0,1) for texture patterns (stateless, so texel order does not matter).
float hash01(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return static_cast<float>(x >> 8) * (1.0f / 16777216.0f);
}

// ---------------------------------------------------------------------------------------------
// Mesh building

class Builder {
 public:
  explicit Builder(SubMesh& m) : m_(m) {}

  std::uint32_t vertex(glm::vec3 p, glm::vec3 n, glm::vec2 uv) {
    m_.positions.push_back(p);
    m_.normals.push_back(n);
    m_.uvs.push_back(uv);
    return static_cast<std::uint32_t>(m_.positions.size() - 1);
  }
  void tri(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    m_.indices.push_back(a);
    m_.indices.push_back(b);
    m_.indices.push_back(c);
  }
  /// Counter-clockwise quad a-b-c-d (front face toward the viewer when CCW).
  void quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    tri(a, b, c);
    tri(a, c, d);
  }
  /// The quads of a lattice of (rows + 1) x (cols + 1) vertices added row by row from `base`: cell
  /// (r, c) has corner a = base + r (cols + 1) + c, wound a, a + 1, a + cols + 2, a + cols + 1
  /// (next column, then next row), or the other way round with `flip`.
  void lattice(std::uint32_t base, int rows, int cols, bool flip = false) {
    const auto row = static_cast<std::uint32_t>(cols + 1);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        const std::uint32_t a = base + static_cast<std::uint32_t>(r) * row + static_cast<std::uint32_t>(c);
        if (flip)
          quad(a, a + row, a + row + 1, a + 1);
        else
          quad(a, a + 1, a + row + 1, a + row);
      }
    }
  }

  /// A planar rectangle origin + s*u + t*v (s,t in [0,1]) in nu x nv cells, front face toward
  /// cross(u, v). uv = (s*|u|, t*|v|) / uv_meters.
  void grid(glm::vec3 origin, glm::vec3 u, glm::vec3 v, int nu, int nv, float uv_meters = 2.0f) {
    nu = std::max(nu, 1);
    nv = std::max(nv, 1);
    const glm::vec3 n = glm::normalize(glm::cross(u, v));
    const float lu = glm::length(u) / uv_meters, lv = glm::length(v) / uv_meters;
    const auto base = static_cast<std::uint32_t>(m_.positions.size());
    for (int j = 0; j <= nv; ++j) {
      for (int i = 0; i <= nu; ++i) {
        const float s = static_cast<float>(i) / static_cast<float>(nu);
        const float t = static_cast<float>(j) / static_cast<float>(nv);
        vertex(origin + u * s + v * t, n, glm::vec2(s * lu, t * lv));
      }
    }
    lattice(base, nv, nu);
  }

  /// An axis-aligned box with outward faces; cells of at most `cell_m` meters per side.
  void box(glm::vec3 lo, glm::vec3 hi, float cell_m = 1e9f) {
    const glm::vec3 e = hi - lo;
    auto cells = [&](float len) { return std::max(1, static_cast<int>(std::ceil(len / cell_m - 1e-4f))); };
    const int cx = cells(e.x), cy = cells(e.y), cz = cells(e.z);
    grid({hi.x, lo.y, hi.z}, {0, 0, -e.z}, {0, e.y, 0}, cz, cy);  // +x
    grid({lo.x, lo.y, lo.z}, {0, 0, e.z}, {0, e.y, 0}, cz, cy);   // -x
    grid({lo.x, hi.y, hi.z}, {e.x, 0, 0}, {0, 0, -e.z}, cx, cz);  // +y
    grid({lo.x, lo.y, lo.z}, {e.x, 0, 0}, {0, 0, e.z}, cx, cz);   // -y
    grid({lo.x, lo.y, hi.z}, {e.x, 0, 0}, {0, e.y, 0}, cx, cy);   // +z
    grid({hi.x, lo.y, lo.z}, {-e.x, 0, 0}, {0, e.y, 0}, cx, cy);  // -z
  }

  /// A surface of revolution about +Y through `center`: profile points (radius, y) bottom to top,
  /// `radial` segments, outward faces and smooth normals.
  void lathe(glm::vec3 center, const std::vector<glm::vec2>& profile, int radial) {
    const auto base = static_cast<std::uint32_t>(m_.positions.size());
    const std::size_t k = profile.size();
    for (std::size_t i = 0; i < k; ++i) {
      const glm::vec2 prev = profile[i == 0 ? 0 : i - 1];
      const glm::vec2 next = profile[i + 1 < k ? i + 1 : k - 1];
      const glm::vec2 tan = next - prev;  // (dr, dy)
      glm::vec2 n2(tan.y, -tan.x);        // outward in (r, y)
      const float len = glm::length(n2);
      n2 = len > 0.0f ? n2 / len : glm::vec2(1.0f, 0.0f);
      for (int j = 0; j <= radial; ++j) {
        const float a = 2.0f * pi * static_cast<float>(j) / static_cast<float>(radial);
        const float c = std::cos(a), s = std::sin(a);
        vertex(center + glm::vec3(profile[i].x * c, profile[i].y, profile[i].x * s), glm::vec3(n2.x * c, n2.y, n2.x * s),
               glm::vec2(static_cast<float>(j) / static_cast<float>(radial), profile[i].y));
      }
    }
    // (i,j) -> (i+1,j) -> (i+1,j+1): outward (see the derivation in docs/scenes.md).
    lattice(base, static_cast<int>(k) - 1, radial, true);
  }

  SubMesh& mesh() { return m_; }

 private:
  SubMesh& m_;
};

// ---------------------------------------------------------------------------------------------
// The scene under construction: materials, textures, sub-meshes and instances.

struct Atrium {
  Scene scene;
  AtriumLayout L;
  int t = 1;  // tessellation factor 2^(detail-1)
  bool colour_texels = true;  // generate the textures' texels (make_atrium's argument)

  std::uint32_t add_material(const std::string& name, AlphaMode mode, glm::vec4 color, int texture,
                             bool double_sided = false, int mask = -1) {
    // Texture i's texels are base_color_texels[i] (add_texture adds both).
    scene.materials.push_back(Material{.name = name, .alpha_mode = mode, .double_sided = double_sided,
                                       .base_color = color, .base_color_texture = texture, .alpha_mask = mask,
                                       .base_color_texels = texture});
    return static_cast<std::uint32_t>(scene.materials.size() - 1);
  }
  /// A w x h texture and its texels: a cells_x x cells_y grid of blocks (stones, tiles, planks),
  /// each a little lighter or darker, with texel noise and darker joints between them, as a
  /// grey the material's colour factor tints (1 x 1 cells: noise only).
  int add_texture(const std::string& name, int w, int h, int cells_x, int cells_y) {
    scene.textures.push_back(TextureInfo{.name = name, .format = "procedural", .width = w, .height = h, .channels = 4});
    const auto seed = static_cast<std::uint32_t>(scene.textures.size()) * 0x9e3779b9U;
    ColorTexels texels{w, h, {}};
    if (!colour_texels) {
      scene.base_color_texels.push_back(std::move(texels));
      return static_cast<int>(scene.textures.size() - 1);
    }
    texels.rgba.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4, 255);
    const int cw = std::max(1, w / cells_x), ch = std::max(1, h / cells_y);
    const int joint_x = cells_x > 1 ? std::max(1, cw / 24) : 0, joint_y = cells_y > 1 ? std::max(1, ch / 24) : 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const int cx = x / cw, cy = y / ch;
        const bool joint = (x % cw) < joint_x || (y % ch) < joint_y;
        const float cell = 0.82f + 0.18f * hash01(seed ^ static_cast<std::uint32_t>(cy * 4099 + cx));
        const float noise = 0.08f * (hash01(seed + static_cast<std::uint32_t>(y * w + x)) - 0.5f);
        const float linear = std::clamp(joint ? 0.5f : cell + noise, 0.0f, 1.0f);
        // Stored sRGB-encoded, as a glTF base colour texture is (ColorTexels decodes it).
        const float srgb = linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
        const auto code = static_cast<std::uint8_t>(std::lround(255.0f * srgb));
        const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)) * 4;
        texels.rgba[i] = texels.rgba[i + 1] = texels.rgba[i + 2] = code;
      }
    }
    scene.base_color_texels.push_back(std::move(texels));
    return static_cast<int>(scene.textures.size() - 1);
  }
  /// A new, empty sub-mesh; returns its index (its storage may move as more are added). Vertices
  /// are position, normal and uv (12 + 12 + 8 = 32 bytes), indices 32-bit.
  std::uint32_t add_submesh(const std::string& name, std::uint32_t material) {
    SubMesh sm;
    sm.name = name;
    sm.material = material;
    sm.vertex_stride_bytes = 32;
    sm.index_bytes = 4;
    scene.submeshes.push_back(std::move(sm));
    return static_cast<std::uint32_t>(scene.submeshes.size() - 1);
  }
  void place(std::uint32_t submesh, const glm::mat4& world, const std::string& node) {
    scene.instances.push_back(Instance{.submesh = submesh, .world = world, .node = node});
  }
};

/// A side of the courtyard: the column line's center, the axis along it, the axis toward the
/// courtyard's middle and the half length to the corner columns.
struct Side {
  const char* name;
  glm::vec3 center;
  glm::vec3 along;
  glm::vec3 inward;
  float half;
  int bays;
};

std::vector<Side> sides(const AtriumLayout& L) {
  const int long_bays = static_cast<int>(std::lround(2.0f * L.court_half_x / L.bay_m));
  const int short_bays = static_cast<int>(std::lround(2.0f * L.court_half_z / L.bay_m));
  return {
      {"north", {0, 0, L.court_half_z}, {1, 0, 0}, {0, 0, -1}, L.court_half_x, long_bays},
      {"south", {0, 0, -L.court_half_z}, {1, 0, 0}, {0, 0, 1}, L.court_half_x, long_bays},
      {"east", {L.court_half_x, 0, 0}, {0, 0, 1}, {-1, 0, 0}, L.court_half_z, short_bays},
      {"west", {-L.court_half_x, 0, 0}, {0, 0, 1}, {1, 0, 0}, L.court_half_z, short_bays},
  };
}

/// World AABB of a box given in a side's frame: along in [a0,a1], inward in [n0,n1], y in [y0,y1].
std::pair<glm::vec3, glm::vec3> side_box(const Side& s, float a0, float a1, float n0, float n1, float y0, float y1) {
  const glm::vec3 p = s.center + s.along * a0 + s.inward * n0;
  const glm::vec3 q = s.center + s.along * a1 + s.inward * n1;
  return {glm::vec3(std::min(p.x, q.x), y0, std::min(p.z, q.z)), glm::vec3(std::max(p.x, q.x), y1, std::max(p.z, q.z))};
}

/// Rotation about Y that maps local +z to `dir` (a horizontal unit vector), keeping +y up.
glm::mat4 facing(glm::vec3 dir) {
  const glm::vec3 up(0, 1, 0);
  const glm::vec3 x = glm::normalize(glm::cross(up, dir));
  glm::mat4 m(1.0f);
  m[0] = glm::vec4(x, 0.0f);
  m[1] = glm::vec4(up, 0.0f);
  m[2] = glm::vec4(dir, 0.0f);
  return m;
}

/// Rotation about Y that maps local +x to the side's along axis.
glm::mat4 side_rotation(const Side& s) {
  const float angle = std::atan2(-s.along.z, s.along.x);
  return glm::rotate(glm::mat4(1.0f), angle, glm::vec3(0, 1, 0));
}

// ---------------------------------------------------------------------------------------------
// Alpha masks

AlphaMask cloth_mask(int w, int h) {
  AlphaMask m{w, h, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), 255)};
  // Moth holes: a dozen circles at hashed places in the body.
  struct Hole { float u, v, r; };
  std::vector<Hole> holes;
  for (std::uint32_t i = 0; i < 14; ++i) {
    holes.push_back({0.1f + 0.8f * hash01(i * 3 + 1), 0.1f + 0.7f * hash01(i * 3 + 2),
                     0.012f + 0.03f * hash01(i * 3 + 3)});
  }
  std::vector<const Hole*> row_holes;
  for (int y = 0; y < h; ++y) {
    const float v = (static_cast<float>(y) + 0.5f) / static_cast<float>(h);
    // The holes this row crosses: where dv * dv >= r * r, du * du + dv * dv < r * r fails for every
    // du (adding a square never rounds below dv * dv), so the others are skipped exactly.
    row_holes.clear();
    for (const Hole& hole : holes) {
      const float dv = (v - hole.v) * static_cast<float>(h);
      const float r = hole.r * static_cast<float>(w);
      if (dv * dv < r * r) row_holes.push_back(&hole);
    }
    for (int x = 0; x < w; ++x) {
      const float u = (static_cast<float>(x) + 0.5f) / static_cast<float>(w);
      bool opaque = true;
      // Swallowtail: the body ends higher in the middle.
      const float body_end = 0.80f + 0.08f * std::abs(2.0f * u - 1.0f);
      if (v > body_end) {
        // Fringe: 48 strands of hashed length below the body.
        const float strand = u * 48.0f;
        const auto si = static_cast<std::uint32_t>(strand);
        const bool in_strand = (strand - static_cast<float>(si)) < 0.55f;
        const float len = 0.05f + 0.07f * hash01(1000u + si);
        opaque = in_strand && v < body_end + len;
      } else {
        // Rod grommets along the top.
        const float gu = u * 10.0f - std::floor(u * 10.0f) - 0.5f;
        const float gv = (v - 0.025f) * static_cast<float>(h) / static_cast<float>(w) * 10.0f;
        if (gu * gu + gv * gv < 0.06f) opaque = false;
        for (const Hole* hole : row_holes) {
          const float du = (u - hole->u) * static_cast<float>(w);
          const float dv = (v - hole->v) * static_cast<float>(h);
          const float r = hole->r * static_cast<float>(w);
          if (du * du + dv * dv < r * r) opaque = false;
        }
      }
      m.alpha[static_cast<std::size_t>(y) * w + x] = opaque ? 255 : 0;
    }
  }
  return m;
}

AlphaMask leaf_mask(int w, int h) {
  AlphaMask m{w, h, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), 0)};
  for (int y = 0; y < h; ++y) {
    // v runs from the leaf's base (row 0) to its tip (last row).
    const float v = (static_cast<float>(y) + 0.5f) / static_cast<float>(h);
    float half = 0.47f * std::pow(std::sin(pi * v), 0.75f) * (1.0f - 0.3f * v);
    half *= 1.0f - 0.08f * (v * 12.0f - std::floor(v * 12.0f));  // serrated edge
    if (v < 0.08f) half = std::max(half, 0.035f);                  // stalk
    for (int x = 0; x < w; ++x) {
      const float u = (static_cast<float>(x) + 0.5f) / static_cast<float>(w);
      const float d = std::abs(u - 0.5f);
      const float coverage = std::clamp((half - d) * static_cast<float>(w) + 0.5f, 0.0f, 1.0f);
      m.alpha[static_cast<std::size_t>(y) * w + x] = static_cast<std::uint8_t>(std::lround(coverage * 255.0f));
    }
  }
  return m;
}

// ---------------------------------------------------------------------------------------------
// Parts (object space)

/// A column: square plinth, lathe-turned shaft with entasis (base moulding and necking ring from
/// detail 2 on), flared capital and abacus. Base at y=0, top (the arch springing) at y=height.
void build_column(Builder& b, float height, int t) {
  const float plinth_h = 0.3f, capital_h = 0.25f, abacus_h = 0.15f;
  const float shaft_r = 0.28f;
  b.box({-0.375f, 0.0f, -0.375f}, {0.375f, plinth_h, 0.375f});
  const float shaft_top = height - capital_h - abacus_h;
  const float shaft_bottom = plinth_h + (t >= 2 ? 0.18f : 0.0f);
  std::vector<glm::vec2> profile;
  if (t >= 2) {
    // Base moulding: a torus-like bulge and a fillet.
    profile.push_back({0.34f, plinth_h});
    profile.push_back({0.36f, plinth_h + 0.06f});
    profile.push_back({0.33f, plinth_h + 0.13f});
  }
  const int hs = 2 * t;
  for (int i = 0; i <= hs; ++i) {
    const float s = static_cast<float>(i) / static_cast<float>(hs);
    const float y = shaft_bottom + s * (shaft_top - shaft_bottom);
    const float entasis = 1.0f + 0.05f * std::sin(pi * std::min(1.0f, s * 1.3f)) - 0.06f * s;
    profile.push_back({shaft_r * entasis, y});
  }
  if (t >= 2) profile.push_back({0.30f, shaft_top + 0.06f});  // necking ring
  // Echinus flaring out to the abacus.
  profile.push_back({0.44f, shaft_top + capital_h});
  b.lathe({0, 0, 0}, profile, 8 * t);
  b.box({-0.42f, height - abacus_h, -0.42f}, {0.42f, height, 0.42f});
}

/// One arcade bay: a wall `depth` thick spanning [-span/2, span/2] in x from the springing (y=0)
/// to `wall_h` above it, pierced by a semicircular arch of radius `radius`; front, back and
/// the intrados (the arch's underside).
void build_arch_bay(Builder& b, float span, float radius, float wall_h, float depth, int t) {
  const int n = 8 * t;           // arc segments (multiple of 4)
  const int rings = std::max(1, t);
  const float hs = span * 0.5f, hd = depth * 0.5f;
  auto arc = [&](int i) {
    const float a = pi * static_cast<float>(i) / static_cast<float>(n);
    return glm::vec2(radius * std::cos(a), radius * std::sin(a));
  };
  // Boundary point matched to arc point i: up the right edge, across the top, down the left edge.
  auto rim = [&](int i) {
    const int q = n / 4;
    if (i <= q) return glm::vec2(hs, wall_h * static_cast<float>(i) / static_cast<float>(q));
    if (i <= 3 * q) return glm::vec2(hs - span * static_cast<float>(i - q) / static_cast<float>(2 * q), wall_h);
    return glm::vec2(-hs, wall_h * static_cast<float>(n - i) / static_cast<float>(q));
  };
  for (int face = 0; face < 2; ++face) {
    const float z = face == 0 ? hd : -hd;
    const glm::vec3 nrm(0, 0, face == 0 ? 1.0f : -1.0f);
    const auto base = static_cast<std::uint32_t>(b.mesh().positions.size());
    for (int i = 0; i <= n; ++i) {
      for (int r = 0; r <= rings; ++r) {
        const glm::vec2 p = glm::mix(arc(i), rim(i), static_cast<float>(r) / static_cast<float>(rings));
        b.vertex({p.x, p.y, z}, nrm, {(p.x + hs) / 2.0f, p.y / 2.0f});
      }
    }
    // The arc index grows counter-clockwise seen from +z (right to left), the ring index
    // outward: (i,r) -> (i,r+1) -> (i+1,r+1) is counter-clockwise seen from +z.
    b.lattice(base, n, rings, face != 0);
  }
  // Intrados: faces toward the arch's center.
  const auto base = static_cast<std::uint32_t>(b.mesh().positions.size());
  for (int i = 0; i <= n; ++i) {
    const glm::vec2 p = arc(i);
    const glm::vec3 nrm(-p.x / radius, -p.y / radius, 0.0f);
    for (int k = 0; k <= rings; ++k) {
      const float z = -hd + depth * static_cast<float>(k) / static_cast<float>(rings);
      b.vertex({p.x, p.y, z}, nrm, {static_cast<float>(i) / static_cast<float>(n), z});
    }
  }
  b.lattice(base, n, rings);
}

/// A hanging banner: top edge at y=0, width w, length h downward, in the z=0 plane with folds
/// displaced along z; uv (0,0) at the top-left seen from +z.
void build_banner(Builder& b, float w, float h, float phase, int t) {
  const int nu = 4 * t, nv = 8 * t;
  const float folds = 3.0f;
  const auto base = static_cast<std::uint32_t>(b.mesh().positions.size());
  for (int j = 0; j <= nv; ++j) {
    const float v = static_cast<float>(j) / static_cast<float>(nv);
    const float amp = 0.05f + 0.10f * v;  // folds deepen toward the hem
    for (int i = 0; i <= nu; ++i) {
      const float u = static_cast<float>(i) / static_cast<float>(nu);
      const float a = 2.0f * pi * folds * u + phase;
      const float z = amp * std::sin(a) + 0.15f * v * v;  // folds plus a slight billow
      const float dzdx = amp * std::cos(a) * 2.0f * pi * folds / w;
      const glm::vec3 n = glm::normalize(glm::vec3(-dzdx, 0.3f * v / h, 1.0f));
      b.vertex({(u - 0.5f) * w, -v * h, z}, n, {u, v});
    }
  }
  // Rows go down (-y) and columns right (+x): (i,j) -> (i,j+1) -> (i+1,j+1) faces +z.
  b.lattice(base, nv, nu, true);
}

/// A plant's foliage: `leaves` folded leaf cards around a crown above y=0, each 4 triangles.
void build_foliage(Builder& b, int leaves, std::uint64_t seed) {
  Pcg32 rng(seed, 7);
  for (int i = 0; i < leaves; ++i) {
    // Stem direction on the upper hemisphere, biased up; leaf starts part way along it.
    float x, y, z;
    do {
      x = rng.range(-1.0f, 1.0f);
      y = rng.range(-0.2f, 1.0f);
      z = rng.range(-1.0f, 1.0f);
    } while (x * x + y * y + z * z > 1.0f || x * x + y * y + z * z < 0.05f);
    const glm::vec3 dir = glm::normalize(glm::vec3(x, y + 0.35f, z));
    const float reach = rng.range(0.15f, 0.75f);
    const glm::vec3 start = glm::vec3(0, 0.1f, 0) + dir * reach * glm::vec3(1.0f, 1.2f, 1.0f);
    // Leaf axis: outward and drooping; width axis horizontal-ish across it.
    glm::vec3 axis = glm::normalize(dir + glm::vec3(0, -rng.range(0.2f, 0.9f), 0));
    glm::vec3 side = glm::cross(axis, glm::vec3(0, 1, 0));
    if (glm::length(side) < 1e-3f) side = glm::vec3(1, 0, 0);
    side = glm::normalize(side);
    // Twist the blade around its axis a little.
    const float twist = rng.range(-0.6f, 0.6f);
    glm::vec3 up = glm::normalize(glm::cross(side, axis));
    side = glm::normalize(side * std::cos(twist) + up * std::sin(twist));
    up = glm::normalize(glm::cross(side, axis));
    const float len = rng.range(0.22f, 0.38f);
    const float wid = len * rng.range(0.38f, 0.5f);
    const float fold = wid * 0.18f;  // midrib raised: a V-shaped blade
    const glm::vec3 tip = start + axis * len;
    const glm::vec3 n = up;
    const std::uint32_t b0 = b.vertex(start - side * (wid * 0.5f), n, {0.0f, 0.0f});
    const std::uint32_t b1 = b.vertex(start + up * fold, n, {0.5f, 0.0f});
    const std::uint32_t b2 = b.vertex(start + side * (wid * 0.5f), n, {1.0f, 0.0f});
    const std::uint32_t t0 = b.vertex(tip - side * (wid * 0.5f) - up * fold, n, {0.0f, 1.0f});
    const std::uint32_t t1 = b.vertex(tip, n, {0.5f, 1.0f});
    const std::uint32_t t2 = b.vertex(tip + side * (wid * 0.5f) - up * fold, n, {1.0f, 1.0f});
    b.quad(b0, t0, t1, b1);
    b.quad(b1, t1, t2, b2);
  }
}

/// A terracotta pot: flared lathe with a rim, base at y=0, rim top at y=0.6.
void build_pot(Builder& b, int t) {
  const std::vector<glm::vec2> key = {{0.0f, 0.0f}, {0.22f, 0.0f}, {0.34f, 0.50f}, {0.38f, 0.60f}, {0.30f, 0.52f}};
  std::vector<glm::vec2> profile;
  for (std::size_t i = 0; i + 1 < key.size(); ++i) {
    for (int k = 0; k < t; ++k) {
      const float s = static_cast<float>(k) / static_cast<float>(t);
      glm::vec2 p = glm::mix(key[i], key[i + 1], s);
      if (i == 1) p.x += 0.03f * std::sin(pi * s);  // belly
      profile.push_back(p);
    }
  }
  profile.push_back(key.back());
  b.lathe({0, 0, 0}, profile, 6 * t);
  // Soil surface.
  b.grid({-0.3f, 0.5f, 0.3f}, {0.6f, 0, 0}, {0, 0, -0.6f}, 1, 1);
}

/// The atrium being built, part by part: its scene, layout and tessellation, the materials, and
/// the dimensions the parts share. Each build_* adds one group of parts (sub-meshes and their
/// instances); make_atrium calls them in a fixed order (the sub-meshes' and instances' order).
struct AtriumParts {
  explicit AtriumParts(Atrium& atrium);

  Atrium& A;
  Scene& S;
  const AtriumLayout& L;
  const int t;  ///< tessellation factor
  std::uint32_t m_stone = 0, m_floor = 0, m_plaster = 0, m_wood = 0, m_terracotta = 0, m_roof = 0, m_cloth_red = 0,
                m_cloth_green = 0, m_cloth_blue = 0, m_foliage = 0, m_glass = 0;
  float cell = 0;            ///< wall, ceiling and roof grid cell, meters
  float depth = 0.75f;       ///< arcade wall thickness
  float hd = 0;              ///< half of it
  float ground_spring = 4.2f, upper_spring = 0;  ///< where the arches spring, per storey
  float ground_ceiling = 0;
  float arch_r = 0;
  std::vector<Side> all_sides;

  /// Grid cells of about `c` meters along `len` meters (at least one).
  static int cells_for(float len, float c) { return std::max(1, static_cast<int>(std::ceil(len / c - 1e-4f))); }
  /// Textures (procedural grey patterns the materials tint, and the two masks) and materials.
  void add_materials();
  /// Floor: courtyard and aisles in one tiled slab, 2/t m cells.
  void build_floor();
  /// Columns, both storeys, instanced along every side (corner columns once).
  void build_columns();
  /// Arcade bays, both storeys; corner piers fill the wall where two arcades meet.
  void build_arcades();
  /// Ledges and cornice along the courtyard side of each arcade (stone), attic walls above the
  /// upper arcade (plaster).
  void build_ledges_and_attic();
  /// Aisles: ceilings (plaster), gallery floor (floor tiles), roof (roof tiles).
  void build_aisles();
  /// Outer walls (plaster): inner and outer faces, wall tops.
  void build_outer_walls();
  /// Wood: ceiling beams across both aisles at every column, doors in the outer walls (the
  /// handrails are the balustrades').
  void build_beams_and_doors();
  /// Glass balustrades between the upper columns, with wooden handrails.
  void build_balustrades();
  /// Glass canopy over the entrance at the west end of the courtyard.
  void build_canopy();
  /// Banners hanging in front of the upper arcades of the long sides, one per bay, colors cycling.
  void build_banners();
  /// Potted plants: in the courtyard along the long arcades and in the ground-floor aisles.
  void build_plants();
};

AtriumParts::AtriumParts(Atrium& atrium) : A(atrium), S(atrium.scene), L(atrium.L), t(atrium.t) {
  add_materials();
  cell = 4.0f / static_cast<float>(t);
  hd = depth * 0.5f;
  upper_spring = L.storey1_height + 3.4f;
  ground_ceiling = L.storey1_height - 0.4f;
  arch_r = L.bay_m * 0.5f - hd;
  all_sides = sides(L);
}

void AtriumParts::add_materials() {
  const int tex_stone = A.add_texture("stone_albedo", 1024, 1024, 4, 8);        // ashlar blocks
  const int tex_floor = A.add_texture("floor_tiles_albedo", 1024, 1024, 8, 8);  // square tiles
  const int tex_plaster = A.add_texture("plaster_albedo", 1024, 1024, 1, 1);    // noise only
  const int tex_wood = A.add_texture("wood_albedo", 512, 512, 1, 16);           // planks
  const int tex_cloth = A.add_texture("cloth_albedo_alpha", 256, 512, 1, 1);
  const int tex_leaf = A.add_texture("leaf_albedo_alpha", 128, 256, 1, 1);
  const int tex_terracotta = A.add_texture("terracotta_albedo", 512, 512, 1, 1);
  const int tex_roof = A.add_texture("roof_tiles_albedo", 512, 512, 8, 16);     // tile rows
  S.alpha_masks.push_back(cloth_mask(256, 512));
  S.alpha_masks.push_back(leaf_mask(128, 256));
  const int mask_cloth = 0, mask_leaf = 1;

  m_stone = A.add_material("stone", AlphaMode::Opaque, {0.72f, 0.68f, 0.60f, 1.0f}, tex_stone);
  m_floor = A.add_material("floor", AlphaMode::Opaque, {0.55f, 0.45f, 0.38f, 1.0f}, tex_floor);
  m_plaster = A.add_material("plaster", AlphaMode::Opaque, {0.85f, 0.80f, 0.70f, 1.0f}, tex_plaster);
  m_wood = A.add_material("wood", AlphaMode::Opaque, {0.42f, 0.27f, 0.14f, 1.0f}, tex_wood);
  m_terracotta = A.add_material("terracotta", AlphaMode::Opaque, {0.70f, 0.36f, 0.22f, 1.0f}, tex_terracotta);
  m_roof = A.add_material("roof_tiles", AlphaMode::Opaque, {0.55f, 0.25f, 0.18f, 1.0f}, tex_roof);
  m_cloth_red = A.add_material("cloth_red", AlphaMode::PunchThrough, {0.65f, 0.08f, 0.07f, 1.0f}, tex_cloth, true, mask_cloth);
  m_cloth_green = A.add_material("cloth_green", AlphaMode::PunchThrough, {0.10f, 0.42f, 0.15f, 1.0f}, tex_cloth, true, mask_cloth);
  m_cloth_blue = A.add_material("cloth_blue", AlphaMode::PunchThrough, {0.10f, 0.16f, 0.55f, 1.0f}, tex_cloth, true, mask_cloth);
  m_foliage = A.add_material("foliage", AlphaMode::PunchThrough, {0.18f, 0.45f, 0.12f, 1.0f}, tex_leaf, true, mask_leaf);
  m_glass = A.add_material("glass", AlphaMode::Translucent, {0.60f, 0.78f, 0.80f, 0.30f}, -1, true);
}

void AtriumParts::build_floor() {
  const std::uint32_t id = A.add_submesh("floor", m_floor);
  Builder b(S.submeshes[id]);
  const float fx = 2.0f * L.outer_half_x, fz = 2.0f * L.outer_half_z;
  b.grid({-L.outer_half_x, 0.0f, L.outer_half_z}, {fx, 0, 0}, {0, 0, -fz}, cells_for(fx, 2.0f / t),
         cells_for(fz, 2.0f / t), 1.0f);
  A.place(id, glm::mat4(1.0f), "floor");
}

void AtriumParts::build_columns() {
  const std::uint32_t ground = A.add_submesh("column_ground", m_stone);
  {
    Builder b(S.submeshes[ground]);
    build_column(b, ground_spring, t);
  }
  const std::uint32_t upper = A.add_submesh("column_upper", m_stone);
  {
    Builder b(S.submeshes[upper]);
    build_column(b, upper_spring - L.storey1_height, t);
  }
  for (const Side& s : all_sides) {
    const bool long_side = s.along.x != 0.0f;
    for (int i = 0; i <= s.bays; ++i) {
      if (!long_side && (i == 0 || i == s.bays)) continue;  // corners belong to the long sides
      const glm::vec3 p = s.center + s.along * (-s.half + L.bay_m * static_cast<float>(i));
      A.place(ground, glm::translate(glm::mat4(1.0f), p), std::string("column_ground_") + s.name + std::to_string(i));
      A.place(upper, glm::translate(glm::mat4(1.0f), p + glm::vec3(0, L.storey1_height, 0)),
              std::string("column_upper_") + s.name + std::to_string(i));
    }
  }
}

void AtriumParts::build_arcades() {
  const std::uint32_t ground = A.add_submesh("arcade_ground", m_stone);
  {
    Builder b(S.submeshes[ground]);
    build_arch_bay(b, L.bay_m, arch_r, ground_ceiling - ground_spring, depth, t);
  }
  const std::uint32_t upper = A.add_submesh("arcade_upper", m_stone);
  {
    Builder b(S.submeshes[upper]);
    build_arch_bay(b, L.bay_m, arch_r, L.storey2_height - upper_spring, depth, t);
  }
  for (const Side& s : all_sides) {
    const glm::mat4 rot = side_rotation(s);
    for (int i = 0; i < s.bays; ++i) {
      const glm::vec3 p = s.center + s.along * (-s.half + L.bay_m * (static_cast<float>(i) + 0.5f));
      A.place(ground, glm::translate(glm::mat4(1.0f), p + glm::vec3(0, ground_spring, 0)) * rot,
              std::string("arcade_ground_") + s.name + std::to_string(i));
      A.place(upper, glm::translate(glm::mat4(1.0f), p + glm::vec3(0, upper_spring, 0)) * rot,
              std::string("arcade_upper_") + s.name + std::to_string(i));
    }
  }
  const std::uint32_t piers = A.add_submesh("corner_piers", m_stone);
  Builder b(S.submeshes[piers]);
  for (float sx : {-1.0f, 1.0f}) {
    for (float sz : {-1.0f, 1.0f}) {
      const glm::vec3 c(sx * L.court_half_x, 0, sz * L.court_half_z);
      b.box(c + glm::vec3(-hd, ground_spring, -hd), c + glm::vec3(hd, ground_ceiling, hd), cell);
      b.box(c + glm::vec3(-hd, upper_spring, -hd), c + glm::vec3(hd, L.storey2_height, hd), cell);
    }
  }
  A.place(piers, glm::mat4(1.0f), "corner_piers");
}

void AtriumParts::build_ledges_and_attic() {
  const std::uint32_t ledges = A.add_submesh("ledges", m_stone);
  const std::uint32_t attic = A.add_submesh("attic_walls", m_plaster);
  struct Band { float y0, y1, back, out; };  // out: protrusion beyond the arcade face
  const Band bands[] = {{ground_ceiling, L.storey1_height, -hd, 0.20f},
                        {L.storey2_height, L.storey2_height + 0.5f, -hd, 0.25f},
                        {L.roof_height - 0.4f, L.roof_height, -hd, 0.40f},
                        {L.roof_height, L.roof_height + 0.3f, -hd - 0.125f, 0.70f}};
  for (const Side& s : all_sides) {
    const bool long_side = s.along.x != 0.0f;
    for (const Band& band : bands) {
      const float front = hd + band.out;
      // Long sides run past the corners; short sides stop where the long ones begin.
      const float a = long_side ? s.half + front : s.half - front;
      auto [lo, hi] = side_box(s, -a, a, band.back, front, band.y0, band.y1);
      Builder(S.submeshes[ledges]).box(lo, hi, 4.0f * cell);
    }
    // Attic wall: courtyard face of the wall between the upper ledge and the cornice.
    const float a = long_side ? s.half + hd : s.half - hd;
    const float y0 = L.storey2_height + 0.5f, y1 = L.roof_height - 0.4f;
    const glm::vec3 left = s.center + s.along * (-a) + s.inward * hd;
    const glm::vec3 right = s.center + s.along * a + s.inward * hd;
    // Front face toward the courtyard: cross(u, v) must point along `inward`.
    glm::vec3 u = right - left;
    const glm::vec3 v(0, y1 - y0, 0);
    glm::vec3 origin = left + glm::vec3(0, y0, 0);
    if (glm::dot(glm::cross(u, v), s.inward) < 0.0f) {
      origin = right + glm::vec3(0, y0, 0);
      u = -u;
    }
    Builder(S.submeshes[attic]).grid(origin, u, v, cells_for(2.0f * a, cell), cells_for(y1 - y0, cell));
  }
  A.place(ledges, glm::mat4(1.0f), "ledges");
  A.place(attic, glm::mat4(1.0f), "attic_walls");
}

void AtriumParts::build_aisles() {
  const std::uint32_t ceilings = A.add_submesh("aisle_ceilings", m_plaster);
  const std::uint32_t gallery_floor = A.add_submesh("gallery_floor", m_floor);
  const std::uint32_t roof = A.add_submesh("roof", m_roof);
  // The aisle band of each side as x/z rectangles: long sides full length, short sides between.
  struct Rect { float x0, x1, z0, z1; };
  const float inner_z = L.court_half_z + hd, inner_x = L.court_half_x + hd;
  const Rect rects[] = {{-L.outer_half_x, L.outer_half_x, inner_z, L.outer_half_z},
                        {-L.outer_half_x, L.outer_half_x, -L.outer_half_z, -inner_z},
                        {inner_x, L.outer_half_x, -inner_z, inner_z},
                        {-L.outer_half_x, -inner_x, -inner_z, inner_z}};
  for (const Rect& r : rects) {
    const float w = r.x1 - r.x0, d = r.z1 - r.z0;
    const int nx = cells_for(w, cell), nz = cells_for(d, cell);
    // Facing down: u = +x, v = +z gives cross = -y.
    Builder(S.submeshes[ceilings]).grid({r.x0, ground_ceiling, r.z0}, {w, 0, 0}, {0, 0, d}, nx, nz);
    Builder(S.submeshes[ceilings]).grid({r.x0, L.storey2_height, r.z0}, {w, 0, 0}, {0, 0, d}, nx, nz);
    // Facing up: u = +x, v = -z.
    Builder(S.submeshes[gallery_floor])
        .grid({r.x0, L.storey1_height, r.z1}, {w, 0, 0}, {0, 0, -d}, cells_for(w, 2.0f / t), cells_for(d, 2.0f / t),
              1.0f);
    Builder(S.submeshes[roof]).grid({r.x0, L.roof_height, r.z1}, {w, 0, 0}, {0, 0, -d}, nx, nz);
  }
  A.place(ceilings, glm::mat4(1.0f), "aisle_ceilings");
  A.place(gallery_floor, glm::mat4(1.0f), "gallery_floor");
  A.place(roof, glm::mat4(1.0f), "roof");
}

void AtriumParts::build_outer_walls() {
  const std::uint32_t walls = A.add_submesh("outer_walls", m_plaster);
  Builder wb(S.submeshes[walls]);
  const float ox = L.outer_half_x, oz = L.outer_half_z, th = 0.5f;
  const float h_in = L.storey2_height, h_out = L.roof_height;
  const float outer_cell = 2.0f * cell;
  // Inner faces (toward the aisles) up to the upper ceiling. Builder::grid's front face points
  // along cross(u, v) with v = +y: u = -x faces -z, +x faces +z, +z faces -x, -z faces +x.
  wb.grid({ox, 0, oz}, {-2 * ox, 0, 0}, {0, h_in, 0}, cells_for(2 * ox, cell), cells_for(h_in, cell));      // north, faces -z
  wb.grid({-ox, 0, -oz}, {2 * ox, 0, 0}, {0, h_in, 0}, cells_for(2 * ox, cell), cells_for(h_in, cell));     // south, faces +z
  wb.grid({ox, 0, -oz}, {0, 0, 2 * oz}, {0, h_in, 0}, cells_for(2 * oz, cell), cells_for(h_in, cell));      // east, faces -x
  wb.grid({-ox, 0, oz}, {0, 0, -2 * oz}, {0, h_in, 0}, cells_for(2 * oz, cell), cells_for(h_in, cell));     // west, faces +x
  // Outer faces (toward the outside), full height, coarser.
  const float ex = ox + th, ez = oz + th;
  wb.grid({-ex, 0, ez}, {2 * ex, 0, 0}, {0, h_out, 0}, cells_for(2 * ex, outer_cell), cells_for(h_out, outer_cell));   // north, faces +z
  wb.grid({ex, 0, -ez}, {-2 * ex, 0, 0}, {0, h_out, 0}, cells_for(2 * ex, outer_cell), cells_for(h_out, outer_cell));  // south, faces -z
  wb.grid({ex, 0, ez}, {0, 0, -2 * ez}, {0, h_out, 0}, cells_for(2 * ez, outer_cell), cells_for(h_out, outer_cell));   // east, faces +x
  wb.grid({-ex, 0, -ez}, {0, 0, 2 * ez}, {0, h_out, 0}, cells_for(2 * ez, outer_cell), cells_for(h_out, outer_cell));  // west, faces -x
  // Wall tops.
  wb.box({-ex, h_out, oz}, {ex, h_out + 0.3f, ez});
  wb.box({-ex, h_out, -ez}, {ex, h_out + 0.3f, -oz});
  wb.box({ox, h_out, -oz}, {ex, h_out + 0.3f, oz});
  wb.box({-ex, h_out, -oz}, {-ox, h_out + 0.3f, oz});
  A.place(walls, glm::mat4(1.0f), "outer_walls");
}

void AtriumParts::build_beams_and_doors() {
  const std::uint32_t beam = A.add_submesh("beam", m_wood);
  const float len = L.aisle_depth - hd;
  Builder(S.submeshes[beam]).box({0.0f, -0.32f, -0.12f}, {len, 0.0f, 0.12f}, cell);
  const std::uint32_t doors = A.add_submesh("doors", m_wood);
  Builder db(S.submeshes[doors]);
  for (const Side& s : all_sides) {
    // The beam's local +x points away from the courtyard, toward the outer wall.
    const glm::vec3 out = -s.inward;
    const float angle = std::atan2(-out.z, out.x);
    const glm::mat4 beam_rot = glm::rotate(glm::mat4(1.0f), angle, glm::vec3(0, 1, 0));
    for (int i = 0; i <= s.bays; ++i) {
      const glm::vec3 p = s.center + s.along * (-s.half + L.bay_m * static_cast<float>(i)) + out * hd;
      for (float y : {ground_ceiling, L.storey2_height}) {
        A.place(beam, glm::translate(glm::mat4(1.0f), p + glm::vec3(0, y, 0)) * beam_rot,
                std::string("beam_") + s.name + std::to_string(i));
      }
    }
    // Doors: centered on the outer wall of each side (two on the long sides).
    const float wall_off = (s.along.x != 0.0f ? L.outer_half_z - L.court_half_z : L.outer_half_x - L.court_half_x);
    const std::vector<float> at = s.along.x != 0.0f ? std::vector<float>{-7.5f, 7.5f} : std::vector<float>{0.0f};
    for (float a : at) {
      auto [lo, hi] = side_box(s, a - 0.8f, a + 0.8f, -wall_off, -wall_off + 0.12f, 0.0f, 2.6f);
      db.box(lo, hi);
      auto [flo, fhi] = side_box(s, a - 0.95f, a + 0.95f, -wall_off, -wall_off + 0.06f, 2.6f, 2.8f);
      db.box(flo, fhi);
    }
  }
  A.place(doors, glm::mat4(1.0f), "doors");
}

void AtriumParts::build_balustrades() {
  const std::uint32_t panel = A.add_submesh("balustrade_glass", m_glass);
  const float pw = L.bay_m - 0.8f, ph = 1.0f;
  Builder(S.submeshes[panel]).grid({-pw * 0.5f, 0.0f, 0.0f}, {pw, 0, 0}, {0, ph, 0}, t, t, 1.0f);
  const std::uint32_t rail = A.add_submesh("handrail", m_wood);
  Builder(S.submeshes[rail])
      .box({-L.bay_m * 0.5f + 0.3f, ph, -0.05f}, {L.bay_m * 0.5f - 0.3f, ph + 0.08f, 0.05f}, cell);
  for (const Side& s : all_sides) {
    const glm::mat4 rot = side_rotation(s);
    for (int i = 0; i < s.bays; ++i) {
      const glm::vec3 p = s.center + s.along * (-s.half + L.bay_m * (static_cast<float>(i) + 0.5f)) +
                          glm::vec3(0, L.storey1_height, 0);
      const glm::mat4 w = glm::translate(glm::mat4(1.0f), p) * rot;
      A.place(panel, w, std::string("balustrade_") + s.name + std::to_string(i));
      A.place(rail, w, std::string("handrail_") + s.name + std::to_string(i));
    }
  }
}

void AtriumParts::build_canopy() {
  const std::uint32_t canopy = A.add_submesh("entrance_canopy", m_glass);
  const float x0 = -L.court_half_x + 0.6f;
  // Sloping down toward the courtyard; front face up.
  Builder(S.submeshes[canopy]).grid({x0, 3.6f, 2.5f}, {3.0f, -0.4f, 0.0f}, {0, 0, -5.0f}, 2 * t, 3 * t, 1.0f);
  A.place(canopy, glm::mat4(1.0f), "entrance_canopy");
}

void AtriumParts::build_banners() {
  const std::uint32_t colors[3] = {m_cloth_red, m_cloth_green, m_cloth_blue};
  const char* color_names[3] = {"red", "green", "blue"};
  std::uint32_t banner[3];
  for (int c = 0; c < 3; ++c) {
    banner[c] = A.add_submesh(std::string("banner_") + color_names[c], colors[c]);
    Builder b(S.submeshes[banner[c]]);
    build_banner(b, 1.9f, 5.0f, 1.3f * static_cast<float>(c), t);
  }
  int side_index = 0;
  for (const Side& s : all_sides) {
    if (s.along.x == 0.0f) continue;
    for (int i = 0; i < s.bays; ++i) {
      const glm::vec3 p = s.center + s.along * (-s.half + L.bay_m * (static_cast<float>(i) + 0.5f)) +
                          s.inward * (hd + 0.45f) + glm::vec3(0, L.storey2_height - 0.05f, 0);
      const int c = (i + side_index) % 3;
      A.place(banner[c], glm::translate(glm::mat4(1.0f), p) * facing(s.inward),
              std::string("banner_") + s.name + std::to_string(i));
    }
    ++side_index;
  }
}

void AtriumParts::build_plants() {
  const std::uint32_t pot = A.add_submesh("pot", m_terracotta);
  {
    Builder b(S.submeshes[pot]);
    build_pot(b, t);
  }
  const int leaves = 24 * t * t;
  std::uint32_t foliage[3];
  for (int v = 0; v < 3; ++v) {
    foliage[v] = A.add_submesh("foliage_" + std::to_string(v), m_foliage);
    Builder b(S.submeshes[foliage[v]]);
    build_foliage(b, leaves, 0xF01A6E00ULL + static_cast<std::uint64_t>(v));
  }
  std::vector<glm::vec3> spots;
  for (const Side& s : all_sides) {
    if (s.along.x == 0.0f) continue;
    for (int i = 0; i < s.bays; i += 2) {
      spots.push_back(s.center + s.along * (-s.half + L.bay_m * (static_cast<float>(i) + 0.5f)) + s.inward * 1.4f);
    }
  }
  for (float sz : {-1.0f, 1.0f}) {
    for (float x : {-12.0f, 0.0f, 12.0f}) spots.push_back({x, 0.0f, sz * (L.outer_half_z - 1.4f)});
  }
  Pcg32 rng(0xA781u, 3);
  int n = 0;
  for (const glm::vec3& p : spots) {
    const float yaw = rng.range(0.0f, 2.0f * pi);
    const float scale = rng.range(0.9f, 1.2f);
    const int variant = static_cast<int>(rng.next() % 3u);
    const glm::mat4 base = glm::translate(glm::mat4(1.0f), p);
    A.place(pot, base, "pot_" + std::to_string(n));
    const glm::mat4 crown = glm::translate(glm::mat4(1.0f), p + glm::vec3(0, 0.55f, 0)) *
                            glm::rotate(glm::mat4(1.0f), yaw, glm::vec3(0, 1, 0)) *
                            glm::scale(glm::mat4(1.0f), glm::vec3(scale));
    A.place(foliage[variant], crown, "plant_" + std::to_string(n));
    ++n;
  }
}

}  // namespace

Scene make_atrium(int detail, bool colour_texels) {
  if (detail < kAtriumMinDetail || detail > kAtriumMaxDetail) {
    throw InputError("atrium:" + std::to_string(detail), "atrium detail must be " + std::to_string(kAtriumMinDetail) +
                                                             ".." + std::to_string(kAtriumMaxDetail));
  }
  Atrium A;
  A.colour_texels = colour_texels;
  A.t = 1 << (detail - 1);
  Scene& S = A.scene;
  S.name = "atrium";
  S.source = "atrium:" + std::to_string(detail);
  S.content_hash = fnv1a_hex(S.source + ":generator" + std::to_string(atrium_generator_version));
  AtriumParts parts(A);
  parts.build_floor();
  parts.build_columns();
  parts.build_arcades();
  parts.build_ledges_and_attic();
  parts.build_aisles();
  parts.build_outer_walls();
  parts.build_beams_and_doors();
  parts.build_balustrades();
  parts.build_canopy();
  parts.build_banners();
  parts.build_plants();
  update_bounds(S);
  return S;
}

}  // namespace tbdr
