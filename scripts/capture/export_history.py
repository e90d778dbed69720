"""Which draw and triangle wrote each pixel of the application's frame, for rdc_export.py.

Two methods give `pixel_history` (`step`, `samples` [x, y, event, primitive]):
- "pixelhistory" (format 1's): RenderDoc's PixelHistory at every sampled pixel; exact, but each
  call replays the events that touch the pixel (about 10 ms a pixel for vkcube, ~1 s on a frame of
  many events).
- "readback" (the default): the final colour target (and the draw's depth target when it writes
  depth) is read before and after every draw that binds it, one GetTextureData each; the last draw
  that changed a pixel is its event, for the whole frame (`draw_ids.bin`). The primitive at a
  sampled pixel is then found from the draw's exported clip positions: the triangles covering the
  pixel centre (viewport, culling, depth clip, top-left rule on 1/256-pixel snapped coordinates)
  resolved by the draw's depth test against the depth target read before the draw. Samples that
  this cannot decide (points, lines, no covering triangle found) fall back to PixelHistory.
A draw that passes every test but writes the colour and depth already there is invisible to the
readback (PixelHistory names it): at the sampled pixels such writes are found from the triangles'
coverage and depth test (draws without discard); in draw_ids.bin the pixel keeps the earlier draw's
event.
"""

import os
import struct

import numpy as np

from export_images import depth_values, is_depth
from export_sd import fail

SNAP = 256.0  # sub-pixel precision of the rasteriser's vertex snapping (lavapipe: 8 bits)
PASS_FLAGS = ("BeginPass", "EndPass", "Clear", "Copy", "Resolve", "GenMips", "Dispatch")


def sample_grid(width, height, samples):
    """(step, [(x, y)]) of a regular grid of about `samples` pixels (format 1's grid)."""
    step = max(1, int((width * height / samples) ** 0.5))
    return step, [(x, y) for y in range(step // 2, height, step) for x in range(step // 2, width, step)]


def pixelhistory_at(rd, c, target, x, y, draw_events):
    """[event, primitive] of the last passing draw at a pixel by RenderDoc's PixelHistory, or [-1, -1]."""
    hit = [-1, -1]
    for m in c.PixelHistory(target, x, y, rd.Subresource(), rd.CompType.Typeless):
        if m.Passed() and m.eventId in draw_events:
            hit = [m.eventId, m.primitiveID]
    return hit


def by_pixelhistory(rd, c, target, grid, draw_events, last_event):
    """Format 1's method: PixelHistory at every sampled pixel."""
    c.SetFrameEvent(last_event, True)
    return [[x, y] + pixelhistory_at(rd, c, target, x, y, draw_events) for x, y in grid]


class Readback:
    """Reads images at an event as numpy arrays (colour: bytes per texel; depth: floats 0..1)."""

    def __init__(self, rd, c, textures, step):
        self.rd = rd
        self.step = step
        self.c = c
        self.textures = textures
        self.reads = 0
        self.replays = 0
        self.event = None  # the replay's current event, when this reader moved it
        self.kept = {}  # (image, event) -> depth read for a draw's test

    def read(self, rid, event):
        """The image's base level at `event`, as (h, w, bytes) uint8 or (h, w) float for depth; None
        for a multisampled depth image (RenderDoc 1.24 crashes reading one on lavapipe after a
        colour read). A multisampled colour image gives its sample 0."""
        t = self.textures[rid]
        if t.msSamp > 1 and is_depth(self.rd, t.format):
            return None
        if event != self.event:
            self.c.SetFrameEvent(event, True)
            self.event = event
            self.replays += 1
        self.reads += 1
        data = self.c.GetTextureData(t.resourceId, self.rd.Subresource())
        if is_depth(self.rd, t.format):
            vals = depth_values(self.rd, t.format, data, t.width * t.height)
            if vals is None:
                return None
            return np.array(vals, dtype=np.float64).reshape(t.height, t.width)
        a = np.frombuffer(bytes(data), dtype=np.uint8)
        n = len(a) // (t.width * t.height)
        return a[:t.width * t.height * n].reshape(t.height, t.width, n)


def changed(before, after):
    """Per pixel: did the image change (any byte or depth); None when either is unreadable."""
    if before is None or after is None or before.shape != after.shape:
        return None
    diff = before != after
    return diff.any(axis=2) if diff.ndim == 3 else diff


def last_writers(rd, rb, actions, draws, target):
    """uint32 (h, w) array: per pixel the event of the last draw that changed the final target (its
    colour, or its depth where the draw writes depth into a same-sized depth target); 0 = none.
    An image read after one draw serves as the next draw's "before" when nothing that could change
    it (pass boundary, clear, transfer, dispatch, another draw) lies between them. The depth read
    before each depth-tested draw is kept (at the sample grid) for its depth test."""
    t = rb.textures[target]
    ids = np.zeros((t.height, t.width), dtype=np.uint32)
    flags = [getattr(rd.ActionFlags, f) for f in PASS_FLAGS + ("Drawcall",)]
    boundaries = sorted(a.eventId for a in actions if any(a.flags & f for f in flags))
    prev_event, prev_colour, prev_depth = None, None, None
    for d in draws:
        if target not in d.get("targets", []):
            continue
        e = d["event"]
        reuse = prev_event is not None and not any(prev_event < b < e for b in boundaries)
        before = prev_colour if reuse else rb.read(target, e - 1)
        dt = d.get("depth_target")
        same_size = dt in rb.textures and (rb.textures[dt].width, rb.textures[dt].height) == (t.width, t.height)
        depth_before = None
        if same_size and d.get("depth_test"):
            depth_before = prev_depth if reuse and prev_depth is not None else rb.read(dt, e - 1)
            if depth_before is not None:
                rb.kept[(dt, e - 1)] = OnGrid(depth_before, rb.step)
        after = rb.read(target, e)
        mask = changed(before, after)
        if mask is None:
            fail("draw at event %d: the final target %d read back at %d bytes a pixel before and %d after"
                 % (e, target, before.shape[-1], after.shape[-1]))
        prev_depth = depth_before if not d.get("depth_write") else None
        if same_size and d.get("depth_write"):
            depth_after = rb.read(dt, e)
            dmask = changed(depth_before if depth_before is not None else rb.read(dt, e - 1), depth_after)
            if dmask is not None:
                mask |= dmask
            prev_depth = depth_after
        ids[mask] = e
        prev_event, prev_colour = e, after
    return ids


class Triangles:
    """A draw's triangles in rasterisation order, for finding the one that wrote a pixel. Framebuffer
    coordinates and bounding boxes are computed once per instance; a pixel tests only the triangles
    whose box holds it."""

    def __init__(self, draw):
        self.draw = draw
        clip = np.array(draw["clip_positions"], dtype=np.float64)
        per = draw.get("vertices_per_instance", len(clip))
        prims = assemble(draw["topology"], draw.get("indices"), per, draw.get("primitive_restart"))
        self.prims = np.array(prims, dtype=np.int64).reshape(-1, 3)
        # Every instance's triangles in one array, instance after instance (rasterisation order):
        # triangle k is primitive k % len(prims) of instance k // len(prims).
        instances = draw.get("instances", 1)
        every = (self.prims[None, :, :] + per * np.arange(instances)[:, None, None]).reshape(-1, 3)
        self.projected = Projected(draw, clip[every] if len(every) else np.zeros((0, 3, 4)))

    def fragments(self, x, y):
        """[(primitive id within its instance, depth)] of the triangles covering pixel (x, y)'s centre,
        in rasterisation order."""
        if not self.projected.may_cover(x + 0.5, y + 0.5):
            return []
        n = max(1, len(self.prims))
        return [(k % n, z) for k, z in self.projected.covering(x + 0.5, y + 0.5)]


class Projected:
    """One instance's triangles (n, 3, 4 clip positions) projected to the framebuffer."""

    def __init__(self, draw, p):
        self.draw = draw
        self.p = p
        vx, vy, vw, vh = draw["viewport"][:4]
        w = p[:, :, 3] if len(p) else np.zeros((0, 3))
        self.positive = (w > 0).all(axis=1) if len(p) else np.zeros(0, dtype=bool)
        self.idx = np.nonzero(self.positive)[0]
        q = p[self.idx]
        with np.errstate(divide="ignore", invalid="ignore"):
            self.sx = np.round((vx + (q[:, :, 0] / q[:, :, 3] + 1) * vw / 2) * SNAP) / SNAP
            self.sy = np.round((vy + (q[:, :, 1] / q[:, :, 3] + 1) * vh / 2) * SNAP) / SNAP
            self.zn = q[:, :, 2] / q[:, :, 3]
        self.box = (self.sx.min(axis=1), self.sx.max(axis=1), self.sy.min(axis=1), self.sy.max(axis=1)) \
            if len(q) else None
        # Triangles with some w <= 0 but not all (wholly behind the eye they are never drawn): their
        # matrices [x; y; w] for homogeneous rasterisation, the singular ones dropped.
        crossing = np.nonzero(~self.positive & (w > 0).any(axis=1))[0] if len(p) else np.zeros(0, dtype=np.int64)
        self.crossing = crossing
        self.hom = None
        if len(crossing):
            m = np.stack([p[crossing, :, 0], p[crossing, :, 1], p[crossing, :, 3]], axis=1)
            det = np.linalg.det(m)
            ok = det != 0
            self.hom = (crossing[ok], m[ok], det[ok]) if ok.any() else None
        self.bounds = None if self.box is None else (self.box[0].min(), self.box[1].max(), self.box[2].min(),
                                                     self.box[3].max())

    def may_cover(self, px, py):
        """False when no triangle can cover (px, py) (outside every box, none crossing w = 0)."""
        if len(self.crossing):
            return True
        b = self.bounds
        return b is not None and b[0] <= px <= b[1] and b[2] <= py <= b[3]

    def covering(self, px, py):
        """[(primitive id, depth 0..1)] of the triangles covering framebuffer point (px, py)."""
        d = self.draw
        sc = d.get("scissor")
        if sc and not (sc[0] <= px < sc[0] + sc[2] and sc[1] <= py < sc[1] + sc[3]):
            return []
        front_ccw = d.get("front_face", "ccw") == "ccw"
        cull = d.get("cull", "none")
        out = []
        if self.box is not None:
            x0, x1, y0, y1 = self.box
            cand = np.nonzero((x0 <= px) & (px <= x1) & (y0 <= py) & (py <= y1))[0]
            if len(cand):
                sx, sy, zn = self.sx[cand], self.sy[cand], self.zn[cand]
                for k in _covers_screen(sx, sy, px, py, cull, front_ccw):
                    out.append((int(self.idx[cand[k]]), float(np.dot(_bary(sx[k], sy[k], px, py), zn[k]))))
        out += self.homogeneous(px, py, cull, front_ccw)
        return self.depth_window(out)

    def homogeneous(self, px, py, cull, front_ccw):
        """Triangles crossing w = 0: homogeneous rasterisation (Olano and Greer 1997), all at once."""
        if self.hom is None:
            return []
        ids, m, det = self.hom
        vx, vy, vw, vh = self.draw["viewport"][:4]
        xn, yn = (px - vx) * 2 / vw - 1, (py - vy) * 2 / vh - 1
        lam = np.linalg.solve(m, np.broadcast_to(np.array([xn, yn, 1.0]), (len(m), 3))[..., None])[..., 0]
        inside = np.nonzero((lam >= 0).all(axis=1))[0]
        return [(int(ids[i]), float(np.dot(lam[i], self.p[ids[i], :, 2]))) for i in inside
                if _faces(det[i] * np.sign(vh), cull, front_ccw)]

    def depth_window(self, frags):
        """Fragments with depth clipped (unless clamped) and mapped to the viewport's depth range, in
        primitive order."""
        d = self.draw
        dmin, dmax = d["viewport"][4:6]
        neg = d.get("depth_clip") == "negative_one_to_one"
        res = []
        for k, z in frags:
            z01 = (z + 1) / 2 if neg else z
            if not d.get("depth_clamp") and not (0.0 <= z01 <= 1.0):
                continue
            res.append((k, dmin + min(max(z01, 0.0), 1.0) * (dmax - dmin)))
        res.sort()
        return res


def assemble(topology, indices, count, restart):
    """Vertex index triples of the triangles of a draw (strip/fan order as Vulkan assembles them;
    a restart index starts a new strip/fan)."""
    idx = list(indices) if indices is not None else list(range(count))
    runs, cur = [], []
    for i in idx:
        if restart is not None and i == restart:
            runs.append(cur)
            cur = []
        else:
            cur.append(i)
    runs.append(cur)
    tris = []
    for r in runs:
        if topology == "triangles":
            tris += [(r[k], r[k + 1], r[k + 2]) for k in range(0, len(r) - 2, 3)]
        elif topology == "triangle_strip":
            tris += [(r[k], r[k + 1], r[k + 2]) if k % 2 == 0 else (r[k + 1], r[k], r[k + 2])
                     for k in range(len(r) - 2)]
        elif topology == "triangle_fan":
            tris += [(r[k + 1], r[k + 2], r[0]) for k in range(len(r) - 2)]
    return tris


def _faces(det_fb, cull, front_ccw):
    """Is a triangle kept by culling, given det([[x],[y],[1]]) of its framebuffer coordinates (Vulkan's
    signed area is -det/2; a positive area is counter-clockwise)."""
    if det_fb == 0:
        return False
    front = (det_fb < 0) == front_ccw
    return not ((cull == "back" and not front) or (cull == "front" and front))


def _covers_screen(sx, sy, px, py, cull, front_ccw):
    """Indices of triangles (framebuffer coordinates sx, sy: (n, 3)) covering (px, py), top-left rule."""
    det = (sx[:, 1] - sx[:, 0]) * (sy[:, 2] - sy[:, 0]) - (sx[:, 2] - sx[:, 0]) * (sy[:, 1] - sy[:, 0])
    inside = np.ones(len(sx), dtype=bool)
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        e = (sx[:, j] - sx[:, i]) * (py - sy[:, i]) - (sy[:, j] - sy[:, i]) * (px - sx[:, i])
        e = e * np.sign(det)  # inside positive whatever the winding
        dy = sy[:, j] - sy[:, i]
        with np.errstate(divide="ignore", invalid="ignore"):
            xe = sx[:, i] + (sy[:, k] - sy[:, i]) * (sx[:, j] - sx[:, i]) / np.where(dy == 0, 1, dy)
        top_left = np.where(dy == 0, sy[:, k] > sy[:, i], sx[:, k] > xe)
        inside &= (e > 0) | ((e == 0) & top_left)
    keep = [n for n in np.nonzero(inside & (det != 0))[0] if _faces(det[n], cull, front_ccw)]
    return keep


def _bary(sx, sy, px, py):
    """Screen-space barycentric weights of (px, py) in one triangle."""
    det = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0])
    l1 = ((px - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (py - sy[0])) / det
    l2 = ((sx[1] - sx[0]) * (py - sy[0]) - (px - sx[0]) * (sy[1] - sy[0])) / det
    return np.array([1 - l1 - l2, l1, l2])


PASSES = {"never": lambda z, d: False, "less": lambda z, d: z < d, "equal": lambda z, d: z == d,
          "less_equal": lambda z, d: z <= d, "greater": lambda z, d: z > d, "not_equal": lambda z, d: z != d,
          "greater_equal": lambda z, d: z >= d, "always": lambda z, d: True}


def quantise(z, fmt_name):
    """A depth value as the depth format stores it (D16/D24 fixed point, else float32)."""
    if "D16" in fmt_name:
        return round(z * 65535) / 65535
    if "D24" in fmt_name or "X8_D24" in fmt_name:
        return round(z * 16777215) / 16777215
    return struct.unpack("<f", struct.pack("<f", z))[0]


def last_passing(draw, frags, depth_before, depth_format):
    """Primitive id of the last fragment passing the draw's depth test, or None."""
    if not frags:
        return None
    if not draw.get("depth_test") or depth_before is None:
        return frags[-1][0] if not draw.get("depth_test") else None
    test = PASSES[draw["depth_compare"]]
    d, hit = depth_before, None
    for prim, z in frags:
        z = quantise(z, depth_format)
        if test(z, d):
            hit = prim
            if draw.get("depth_write"):
                d = z
    return hit


def cpu_decidable(d):
    """Can the CPU test decide a draw's writes: triangles without discard (it knows triangles, viewport,
    scissor, culling, depth clip and the depth test, not discards or stencil)."""
    return d["topology"].startswith("triangle") and not d.get("shader", {}).get("discard")


def unchanged_writes(rb, draws, target, grid, ids, textures):
    """{sample index: event} where a later draw passes at a sampled pixel without changing it (it
    wrote the colour and depth already there, e.g. a transparent texel of a 2D quad): the last draw
    on the final target whose triangles cover the pixel centre and pass its depth test (against the
    depth read back before it) owns the sample, as PixelHistory names it."""
    later = [d for d in draws if target in d.get("targets", []) and cpu_decidable(d)]
    owner = {}
    for d in reversed(later):
        todo = [n for n, (x, y) in enumerate(grid) if n not in owner and int(ids[y, x]) < d["event"]]
        if not todo:
            continue
        tris = Triangles(d)
        frags = {n: tris.fragments(*grid[n]) for n in todo}
        frags = {n: f for n, f in frags.items() if f}
        if not frags:
            continue
        depth, fmt = depth_before(rb, d, textures)
        if d.get("depth_test") and depth is None:
            continue
        for n, f in frags.items():
            x, y = grid[n]
            if last_passing(d, f, float(depth[y, x]) if depth is not None else None, fmt) is not None:
                owner[n] = d["event"]
    return owner


def depth_before(rb, d, textures):
    """(the draw's depth target read just before it, or None; its format name) for its depth test.
    Kept per draw (both passes over the samples ask), as the values at the sampled pixels only."""
    dt = d.get("depth_target")
    if not d.get("depth_test") or dt not in textures:
        return None, ""
    key = (dt, d["event"] - 1)
    if key not in rb.kept:
        full = rb.read(dt, d["event"] - 1)
        rb.kept[key] = None if full is None else OnGrid(full, rb.step)
    return rb.kept[key], textures[dt].format.Name()


class OnGrid:
    """An image's values at the sample grid's pixels only (x, y = step // 2 + k * step)."""

    def __init__(self, full, step):
        self.step = step
        self.values = full[step // 2::step, step // 2::step].copy()

    def __getitem__(self, yx):
        """The value at pixel (y, x) of the grid; NaN outside the image (no depth test passes)."""
        r, c = (yx[0] - self.step // 2) // self.step, (yx[1] - self.step // 2) // self.step
        if 0 <= r < self.values.shape[0] and 0 <= c < self.values.shape[1]:
            return self.values[r, c]
        return float("nan")


def by_readback(rd, c, actions, draws, target, step, grid, textures, outdir, log):
    """The readback method (module docstring); writes draw_ids.bin into outdir. Returns the samples."""
    rb = Readback(rd, c, textures, step)
    ids = last_writers(rd, rb, actions, draws, target)
    with open(os.path.join(outdir, "draw_ids.bin"), "wb") as f:
        f.write(ids.astype("<u4").tobytes())
    by_event = {d["event"]: d for d in draws}
    owner = unchanged_writes(rb, draws, target, grid, ids, textures)
    pending = {}
    for n, (x, y) in enumerate(grid):
        pending.setdefault(owner.get(n, int(ids[y, x])), []).append(n)
    samples = [None] * len(grid)
    fallback = []
    for e, ns in sorted(pending.items()):
        if e == 0:
            for n in ns:
                samples[n] = [grid[n][0], grid[n][1], -1, -1]
            continue
        d = by_event[e]
        if not d["topology"].startswith("triangle"):
            fallback += ns  # points and lines
            continue
        tris = Triangles(d)
        depth, fmt = depth_before(rb, d, textures)  # None when multisampled: PixelHistory decides
        for n in ns:
            x, y = grid[n]
            before = float(depth[y, x]) if depth is not None else None
            prim = last_passing(d, tris.fragments(x, y), before, fmt)
            if prim is None:
                fallback.append(n)
            else:
                samples[n] = [x, y, e, prim]
    if fallback:
        c.SetFrameEvent(max(a.eventId for a in actions), True)
        events = set(by_event)
        for n in fallback:
            x, y = grid[n]
            samples[n] = [x, y] + pixelhistory_at(rd, c, textures[target].resourceId, x, y, events)
    log["readbacks"] = rb.reads
    log["replays"] = rb.replays
    log["pixelhistory_fallbacks"] = len(fallback)
    return samples
