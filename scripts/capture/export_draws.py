"""One draw of a Vulkan capture for rdc_export.py: pipeline state, post-vertex-shader geometry of
every instance, the vertex and fragment shaders' static SPIR-V cost, the bound textures.

State that changes what clip coordinates or depth mean is either carried (depth_clip, depth_clamp,
depth_bias) or the export fails naming the event and the state: nothing is exported with a
silently changed meaning.
"""

import os
import struct

import spirv_cost
from export_images import save_texture
from export_sd import fail

COMPARE = {"Never": "never", "Less": "less", "Equal": "equal", "LessEqual": "less_equal", "Greater": "greater",
           "NotEqual": "not_equal", "GreaterEqual": "greater_equal", "AlwaysTrue": "always"}
# RenderDoc topology name -> the intermediate's; anything else (adjacency, patches) is refused by name.
TOPOLOGIES = {"TriangleList": "triangles", "TriangleStrip": "triangle_strip", "TriangleFan": "triangle_fan",
              "LineList": "lines", "LineStrip": "line_strip", "PointList": "points"}


def enum_name(enum, value, what="topology"):
    """The RenderDoc name of an enum value (e.g. Topology.TriangleList_Adj -> TriangleList_Adj), never
    a bare number."""
    for name in dir(enum):
        if name[:1].isupper() and getattr(enum, name) == value:
            return name
    return "%s %s" % (what, value)


def topology_name(rd, value):
    """The RenderDoc name of a Topology value."""
    return enum_name(rd.Topology, value)


class DrawReader:
    """Exports draws; keeps the textures already saved so each is written once."""

    def __init__(self, rd, c, textures, outdir, unsupported):
        self.rd = rd
        self.c = c
        self.textures = textures
        self.outdir = outdir
        self.unsupported = unsupported
        self.saved = {}

    def export(self, a, name):
        """The frame.json entry of draw action `a` (the replay is moved to its event)."""
        rd, c = self.rd, self.c
        c.SetFrameEvent(a.eventId, True)
        where = "draw at event %d (%s)" % (a.eventId, name)
        vk = c.GetVulkanPipelineState()
        ps = c.GetPipelineState()
        draw = {"event": a.eventId, "name": name}
        topo = topology_name(rd, ps.GetPrimitiveTopology())
        if topo not in TOPOLOGIES:
            fail("%s: topology %s is not imported (points, lines, line strips and triangles only)" % (where, topo))
        self.refuse_stages(vk, where)
        self.viewport(vk, draw, where)
        self.depth_meaning(vk, draw, where)
        self.raster_state(vk, draw, topo, where)
        self.depth_stencil(vk, draw, where)
        self.blend(vk, draw, where)
        self.fragment_shader(ps, draw, where)
        vs = ps.GetShaderReflection(rd.ShaderStage.Vertex)
        if vs is None:
            fail("%s: no vertex shader bound" % where)
        draw["vertex_shader"] = self.vertex_shader_cost(vs, where)
        bound = self.textures_of(a, ps, draw)
        draw["topology"] = TOPOLOGIES[topo]
        self.geometry(a, vs, draw, where, len(bound) == 1)
        targets = [t.resourceId for t in ps.GetOutputTargets() if t.resourceId != rd.ResourceId.Null()]
        draw["targets"] = [int(t) for t in targets]
        depth = ps.GetDepthTarget().resourceId
        draw["depth_target"] = int(depth) if depth != rd.ResourceId.Null() else None
        return draw

    # -- state ---------------------------------------------------------------------------------

    def refuse_stages(self, vk, where):
        """Tessellation and geometry stages: the positions RenderDoc gives (VSOut) are not what is
        rasterised, so the export fails naming the stage."""
        for stage, sh in (("tessellation control", vk.tessControlShader), ("tessellation evaluation",
                                                                            vk.tessEvalShader),
                          ("geometry", vk.geometryShader)):
            if sh.resourceId != self.rd.ResourceId.Null():
                fail("%s: a %s shader is bound; its output (what is rasterised) is not exported" % (where, stage))
        if vk.transformFeedback.rasterizedStream not in (0,):
            fail("%s: transform feedback rasterises stream %d" % (where, vk.transformFeedback.rasterizedStream))

    def viewport(self, vk, draw, where):
        """viewport [x, y, w, h, min depth, max depth] and scissor [x, y, w, h] (the first of each)."""
        vps = vk.viewportScissor.viewportScissors
        if not vps:
            fail("%s: no viewport bound" % where)
        vp, sc = vps[0].vp, vps[0].scissor
        draw["viewport"] = [vp.x, vp.y, vp.width, vp.height, vp.minDepth, vp.maxDepth]
        draw["scissor"] = [sc.x, sc.y, sc.width, sc.height]
        if len(vps) > 1:
            self.unsupported.append("%s: %d viewports; only the first is imported" % (where, len(vps)))

    def depth_meaning(self, vk, draw, where):
        """depth_clip (VK_EXT_depth_clip_control), depth_clamp, depth_bias; fails on depth clipping
        turned off without a clamp (VK_EXT_depth_clip_enable), which the intermediate cannot express."""
        r = vk.rasterizer
        draw["depth_clip"] = "negative_one_to_one" if vk.viewportScissor.depthNegativeOneToOne else "zero_to_one"
        draw["depth_clamp"] = bool(r.depthClampEnable)
        # zink enables depth bias in every pipeline and sets the factors dynamically (0 unless
        # glPolygonOffset): enabled with zero factors changes nothing, so depth_bias says whether it
        # has an effect; the enable and the factors are recorded.
        draw["depth_bias"] = bool(r.depthBiasEnable and (r.depthBias != 0 or r.slopeScaledDepthBias != 0))
        if r.depthBiasEnable:
            draw["depth_bias_values"] = [r.depthBias, r.depthBiasClamp, r.slopeScaledDepthBias]
            if not draw["depth_bias"]:
                draw.setdefault("state_notes", []).append("depth bias enabled with zero factors (no effect)")
        if not r.depthClipEnable and not r.depthClampEnable:
            fail("%s: depth clipping disabled (VK_EXT_depth_clip_enable) without depth clamp: primitives beyond "
                 "the near and far planes are neither clipped nor clamped, which the intermediate cannot express"
                 % where)
        if r.depthClipEnable and r.depthClampEnable:
            draw.setdefault("state_notes", []).append("depth clamp with depth clipping kept on "
                                                      "(VK_EXT_depth_clip_enable)")
            draw["depth_clip_enable"] = True

    def raster_state(self, vk, draw, topo, where):
        """cull, front_face, line_width; fill mode, discard and conservative rasterisation are noted."""
        rd, r = self.rd, vk.rasterizer
        draw["cull"] = {rd.CullMode.NoCull: "none", rd.CullMode.Back: "back", rd.CullMode.Front: "front"}.get(
            r.cullMode)
        if draw["cull"] is None:
            # VK_CULL_MODE_FRONT_AND_BACK: every triangle is culled (lines and points still draw);
            # the importer draws the triangles of none of it, never as cull none.
            draw["cull"] = "front_and_back"
        draw["front_face"] = "ccw" if r.frontCCW else "cw"
        if topo.startswith("Line") or r.fillMode == rd.FillMode.Wireframe:
            draw["line_width"] = r.lineWidth
            if r.lineRasterMode != rd.LineRaster.Default:
                draw.setdefault("state_notes", []).append("line rasterisation %s"
                                                          % enum_name(rd.LineRaster, r.lineRasterMode, "mode"))
            if r.lineStippleFactor:
                self.unsupported.append("%s: line stipple (factor %d) not imported" % (where, r.lineStippleFactor))
        if r.fillMode != rd.FillMode.Solid and not (topo.startswith("Line") or topo.startswith("Point")):
            # Wireframe or point polygons draw edges or corners where filled triangles would cover
            # the whole face: a geometry the application did not have.
            fail("%s: polygon mode %s (VkPipelineRasterizationStateCreateInfo::polygonMode) is not imported; "
                 "its triangles would be filled" % (where, enum_name(rd.FillMode, r.fillMode, "mode")))
        if r.rasterizerDiscardEnable:
            fail("%s: rasterizer discard enabled (the draw rasterises nothing)" % where)
        if r.conservativeRasterization != rd.ConservativeRaster.Disabled:
            self.unsupported.append("%s: conservative rasterisation imported as standard" % where)

    def depth_stencil(self, vk, draw, where):
        """depth_test, depth_write, depth_compare; stencil is listed as unsupported."""
        ds = vk.depthStencil
        draw["depth_test"] = bool(ds.depthTestEnable)
        draw["depth_write"] = bool(ds.depthTestEnable and ds.depthWriteEnable)
        draw["depth_compare"] = {getattr(self.rd.CompareFunction, k): v for k, v in COMPARE.items()}.get(
            ds.depthFunction)
        if draw["depth_compare"] is None:
            fail("%s: depth compare %s not known" % (where, ds.depthFunction))
        if ds.stencilTestEnable:
            self.unsupported.append("%s: stencil test enabled; imported without it" % where)
        if ds.depthBoundsEnable:
            self.unsupported.append("%s: depth bounds test enabled; imported without it" % where)

    def blend(self, vk, draw, where):
        """blend off/alpha/add of the first colour target, and blend_factors [src, dst, op] for the record."""
        blends = vk.colorBlend.blends
        draw["blend"] = "off"
        if blends and blends[0].enabled:
            b = blends[0].colorBlend
            src, dst, op = b.source.name, b.destination.name, b.operation.name
            draw["blend_factors"] = [src, dst, op]
            if src == "SrcAlpha" and dst == "InvSrcAlpha":
                draw["blend"] = "alpha"
            elif src == "One" and dst == "One":
                draw["blend"] = "add"
            else:
                self.unsupported.append("%s: blend %s/%s imported as alpha blending" % (where, src, dst))
                draw["blend"] = "alpha"

    # -- shaders -------------------------------------------------------------------------------

    @staticmethod
    def static_cost(refl, stage, where):
        """spirv_cost.shader_cost of a shader's SPIR-V; fails naming the stage on a bad module."""
        try:
            return spirv_cost.shader_cost(bytes(refl.rawBytes))
        except spirv_cost.SpirvError as e:
            fail("%s: %s shader: %s" % (where, stage, e))

    def fragment_shader(self, ps, draw, where):
        """`shader`: the fragment shader's static SPIR-V cost (as in format 1)."""
        rd = self.rd
        fs = ps.GetShaderReflection(rd.ShaderStage.Fragment)
        if fs is None:
            draw["shader"] = {"alu_ops": 0, "tex_fetches": 0, "varyings": 0, "color_outputs": 0, "discard": False,
                              "source": "no fragment shader"}
            return
        cost = self.static_cost(fs, "fragment", where)
        if cost["loops"]:
            self.unsupported.append("%s: fragment shader has %d loop(s); each body is counted once (static count)"
                                    % (where, cost["loops"]))
        varyings = sum(s.compCount for s in fs.inputSignature if s.systemValue == rd.ShaderBuiltin.Undefined)
        # zink declares 8 colour outputs for gl_FragColor (it broadcasts to every draw buffer): the
        # outputs counted are those whose location has a bound colour target.
        bound = [t.resourceId != rd.ResourceId.Null() for t in ps.GetOutputTargets()]
        declared = [s for s in fs.outputSignature if s.systemValue == rd.ShaderBuiltin.ColorOutput]
        outputs = sum(1 for s in declared if s.regIndex < len(bound) and bound[s.regIndex])
        draw["shader"] = {"alu_ops": cost["alu_ops"], "tex_fetches": cost["tex_fetches"], "varyings": varyings,
                          "color_outputs": outputs, "discard": cost["discard"], "loads": cost["loads"],
                          "stores": cost["stores"], "branches": cost["branches"], "loops": cost["loops"],
                          "source": "spirv static count, %d instructions" % cost["instructions"],
                          "entry": fs.entryPoint, "shader_id": int(fs.resourceId)}
        if outputs != len(declared):
            draw["shader"]["color_outputs_declared"] = len(declared)

    def vertex_shader_cost(self, vs, where):
        """`vertex_shader`: static SPIR-V cost plus `outputs`, the 32-bit components it writes besides
        gl_Position (`varyings`: those of its own outputs, without built-ins such as gl_PointSize)."""
        rd = self.rd
        cost = self.static_cost(vs, "vertex", where)
        comps = [(s, s.compCount * (2 if _is_double(rd, s) else 1)) for s in vs.outputSignature]
        out = {k: cost[k] for k in ("alu_ops", "tex_fetches", "loads", "stores", "branches", "loops", "instructions")}
        out["source"] = "spirv static count, %d instructions" % cost["instructions"]
        out["outputs"] = sum(n for s, n in comps if s.systemValue != rd.ShaderBuiltin.Position)
        out["varyings"] = sum(n for s, n in comps if s.systemValue == rd.ShaderBuiltin.Undefined)
        out["entry"] = vs.entryPoint
        out["shader_id"] = int(vs.resourceId)
        return out

    # -- textures ------------------------------------------------------------------------------

    def textures_of(self, a, ps, draw):
        """`textures`: the images the fragment shader reads, each saved once as a PNG when its format
        allows (8-bit colour as RGB, R8/RG8 as grey, depth as normalised grey), else listed."""
        rd, c = self.rd, self.c
        bound = []
        for used in ps.GetReadOnlyResources(rd.ShaderStage.Fragment):
            for res in used.resources:
                rid = int(res.resourceId)
                if rid in self.textures and rid not in bound:
                    bound.append(rid)
        draw["textures"] = []
        for rid in bound:
            t = self.textures[rid]
            if rid not in self.saved:
                fname = "tex_%d.png" % rid
                # Read at the draw's event, where export() has put the replay (each replay of a large
                # frame costs about a second on lavapipe).
                ok, note = save_texture(rd, c, t, os.path.join(self.outdir, fname), None)
                self.saved[rid] = (fname if ok else None, note)
                if not ok:
                    self.unsupported.append("draw at event %d: texture %d not saved: %s" % (a.eventId, rid, note))
            fname, note = self.saved[rid]
            entry = {"id": rid, "width": t.width, "height": t.height, "format": t.format.Name(), "mips": t.mips}
            if fname:
                entry["file"] = fname
            if note:
                entry["note"] = note
            draw["textures"].append(entry)
        return bound

    # -- geometry ------------------------------------------------------------------------------

    def geometry(self, a, vs, draw, where, want_uvs):
        """clip_positions (every instance's vertices concatenated), indices (within one instance),
        instances, vertices_per_instance, point_sizes and uvs when present."""
        rd, c = self.rd, self.c
        instances = max(1, a.numInstances)
        m0 = c.GetPostVSData(0, 0, rd.MeshDataStage.VSOut)
        if m0.vertexResourceId == rd.ResourceId.Null() or m0.numIndices == 0:
            fail("%s: RenderDoc has no vertex shader output for it" % where)
        indices, nverts = self.read_indices(m0, draw, where)
        offsets = output_offsets(rd, vs)
        psize = next((off for s, off in offsets if s.systemValue == rd.ShaderBuiltin.PointSize), None)
        if draw["topology"] != "points":
            psize = None  # zink writes gl_PointSize in every vertex shader; it matters for points only
        uv_sig = None
        if want_uvs:
            uv_sig = next(((s, off) for s, off in offsets if s.systemValue == rd.ShaderBuiltin.Undefined
                           and s.compCount >= 2 and off + 8 <= m0.vertexByteStride), None)
        clip, sizes, uvs = [], [], []
        for inst in range(instances):
            m = m0 if inst == 0 else c.GetPostVSData(inst, 0, rd.MeshDataStage.VSOut)
            if m.numIndices != m0.numIndices or m.vertexByteStride != m0.vertexByteStride:
                fail("%s: instance %d's vertex shader output differs in shape from instance 0's" % (where, inst))
            data = c.GetBufferData(m.vertexResourceId, m.vertexByteOffset, nverts * m.vertexByteStride)
            if len(data) < nverts * m.vertexByteStride:
                fail("%s: instance %d: vertex shader output is %d bytes, %d vertices of %d bytes expected"
                     % (where, inst, len(data), nverts, m.vertexByteStride))
            stride = m.vertexByteStride
            clip += [list(struct.unpack_from("<4f", data, v * stride)) for v in range(nverts)]
            if psize is not None:
                sizes += [struct.unpack_from("<f", data, v * stride + psize)[0] for v in range(nverts)]
            if uv_sig is not None:
                uvs += [list(struct.unpack_from("<2f", data, v * stride + uv_sig[1])) for v in range(nverts)]
        draw["clip_positions"] = clip
        if indices is not None:
            draw["indices"] = indices
        draw["vertex_stride_bytes"] = m0.vertexByteStride
        draw["instances"] = instances
        draw["vertices_per_instance"] = nverts
        draw["first_instance"] = a.instanceOffset
        if psize is not None:
            draw["point_sizes"] = sizes
        if uv_sig is not None:
            draw["uvs"] = uvs
            draw["uv_source"] = "vertex output '%s' (heuristic: first non-builtin output)" % uv_sig[0].varName

    def read_indices(self, m, draw, where):
        """(indices or None, vertex count) of RenderDoc's VS output mesh; a primitive restart index in
        the indices is kept and named (`primitive_restart`)."""
        count = m.numIndices
        if m.indexResourceId == self.rd.ResourceId.Null() or not m.indexByteStride:
            return None, count
        raw = self.c.GetBufferData(m.indexResourceId, m.indexByteOffset, count * m.indexByteStride)
        fmt = {1: "B", 2: "H", 4: "I"}.get(m.indexByteStride)
        if fmt is None or len(raw) < count * m.indexByteStride:
            fail("%s: index data of %d bytes for %d indices of %d bytes" % (where, len(raw), count, m.indexByteStride))
        indices = list(struct.unpack("<%d%s" % (count, fmt), raw[:count * m.indexByteStride]))
        restart = m.restartIndex & ((1 << (8 * m.indexByteStride)) - 1) if m.allowRestart else None
        real = [i for i in indices if i != restart]
        if restart is not None and len(real) != len(indices):
            draw["primitive_restart"] = restart
        return indices, (max(real) + 1 if real else 0)


def _is_double(rd, sig):
    """True for a 64-bit output (two 32-bit components each)."""
    return sig.varType in (rd.VarType.Double, rd.VarType.SLong, rd.VarType.ULong)


def output_offsets(rd, vs):
    """(signature entry, byte offset) of each vertex shader output in RenderDoc's VS output buffer:
    std430 packing in signature order, built-ins (gl_Position) first (vk_postvs.cpp of 1.24)."""
    out, off = [], 0
    for s in vs.outputSignature:
        elem = 8 if _is_double(rd, s) else 4
        if s.compCount == 2:
            off = (off + 2 * elem - 1) // (2 * elem) * (2 * elem)
        elif s.compCount > 2:
            off = (off + 4 * elem - 1) // (4 * elem) * (4 * elem)
        out.append((s, off))
        off += elem * s.compCount
    return out
