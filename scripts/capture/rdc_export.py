#!/usr/bin/python3
"""Exports one frame of a RenderDoc capture (.rdc) to tbdrsim's capture intermediate (frame.json).

usage: rdc_export.py CAPTURE.rdc OUTDIR [--history-samples N]

Runs RenderDoc's replay (python3-renderdoc, Debian's /usr/bin/python3) and writes into OUTDIR:
  frame.json     passes, attachments (load/store/clear), per draw: pipeline state, post-vertex-shader
                 clip positions (gl_Position as the vertex shader wrote it), the fragment shader's
                 static SPIR-V cost, bound textures; dispatches; what was not supported
  reference.png  the application's own final colour image (the last render pass's first colour target)
  tex_<id>.png   the sampled textures a draw binds (its base colour when uvs are exported)
The format of frame.json is docs/capture-import.md ("The intermediate"); `tbdrsim import` turns it
into a trace and a GLB. Errors: one line naming the event (draw) at fault, exit 2, nothing written.
Only Vulkan captures are read (RenderDoc captures GL too, but the load/store ops read here are
Vulkan's render pass objects).
"""

import json
import os
import struct
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import spirv_cost  # noqa: E402

PROG = os.environ.get("TBDRSIM_PLOT_PROG", "rdc_export.py")


class ExportError(Exception):
    """A capture that cannot be exported; the message names the event or resource."""


def fail(msg):
    raise ExportError(msg)


def enum_tail(s, prefix):
    """VK_ATTACHMENT_LOAD_OP_CLEAR -> clear."""
    return s[len(prefix):].lower() if s.startswith(prefix) else s.lower()


def child(obj, name):
    c = obj.FindChild(name)
    if c is None:
        fail("capture structure: %s has no member '%s'" % (obj.name, name))
    return c


def children(obj):
    return [obj.GetChild(i) for i in range(obj.NumChildren())]


LOAD_OPS = {"clear": "clear", "load": "load", "dont_care": "dont_care", "none_ext": "dont_care", "none_khr": "dont_care"}
STORE_OPS = {"store": "store", "dont_care": "dont_care", "none": "dont_care", "none_khr": "dont_care",
             "none_ext": "dont_care", "none_qcom": "dont_care"}
COMPARE = {"Never": "never", "Less": "less", "Equal": "equal", "LessEqual": "less_equal", "Greater": "greater",
           "NotEqual": "not_equal", "GreaterEqual": "greater_equal", "AlwaysTrue": "always"}


def export(rdc_path, outdir, history_samples):
    import renderdoc as rd  # python3-renderdoc; imported here so --help works without it

    if not os.path.isfile(rdc_path):
        fail("%s: capture file not found" % rdc_path)
    # A RenderDoc capture starts with the magic "RDOC" (renderdoc/serialise/rdcfile.cpp): anything
    # else is refused before RenderDoc starts its replay threads.
    with open(rdc_path, "rb") as f:
        magic = f.read(4)
    if magic != b"RDOC":
        fail("%s: not a RenderDoc capture (it does not start with the magic RDOC)" % rdc_path)
    rd.InitialiseReplay(rd.GlobalEnvironment(), [])
    cap = None
    c = None
    # Every way out shuts RenderDoc down first: a process leaving with its replay threads running
    # can hang at exit.
    try:
        cap = rd.OpenCaptureFile()
        status = cap.OpenFile(rdc_path, "", None)
        if status != rd.ResultCode.Succeeded:
            fail("%s: RenderDoc cannot open it (%s): not a capture, or truncated" % (rdc_path, status))
        if cap.LocalReplaySupport() != rd.ReplaySupport.Supported:
            fail("%s: this machine cannot replay a %s capture (RenderDoc: %s)" % (rdc_path, cap.DriverName(),
                                                                                 cap.LocalReplaySupport()))
        api = cap.DriverName()
        if api != "Vulkan":
            fail("%s: a %s capture; only Vulkan captures are imported (docs/capture-import.md)" % (rdc_path, api))
        status, c = cap.OpenCapture(rd.ReplayOptions(), None)
        if status != rd.ResultCode.Succeeded:
            c = None
            fail("%s: RenderDoc cannot replay it (%s)" % (rdc_path, status))
        return export_replay(rd, c, rdc_path, outdir, history_samples, api)
    finally:
        if c is not None:
            c.Shutdown()
        if cap is not None:
            cap.Shutdown()
        rd.ShutdownReplay()


def export_replay(rd, c, rdc_path, outdir, history_samples, api):
    sf = c.GetStructuredFile()
    resources = {int(r.resourceId): r for r in c.GetResources()}
    textures = {int(t.resourceId): t for t in c.GetTextures()}
    unsupported = []
    actions = []

    def walk(a):
        actions.append(a)
        for ch in a.children:
            walk(ch)

    for a in c.GetRootActions():
        walk(a)

    def chunk_of(action, want):
        for ev in action.events:
            ch = sf.chunks[ev.chunkIndex]
            if ch.name == want:
                return ch
        return None

    def render_pass_desc(begin_action):
        """Attachments (format, samples, load, store, clear) of a vkCmdBeginRenderPass."""
        ch = chunk_of(begin_action, "vkCmdBeginRenderPass") or chunk_of(begin_action, "vkCmdBeginRenderPass2")
        if ch is None:
            fail("event %d (%s): render pass begun by %s, which is not imported (dynamic rendering?)"
                 % (begin_action.eventId, begin_action.GetName(sf), begin_action.GetName(sf)))
        begin = child(ch, "RenderPassBegin")
        rp_id = int(child(begin, "renderPass").AsResourceId())
        clears = []
        for cv in children(child(begin, "pClearValues")):
            col = [f.AsFloat() for f in children(child(child(cv, "color"), "float32"))]
            ds = child(cv, "depthStencil")
            clears.append({"color": col, "depth": child(ds, "depth").AsFloat(), "stencil": child(ds, "stencil").AsInt()})
        rp = resources.get(rp_id)
        if rp is None or not rp.initialisationChunks:
            fail("event %d: render pass %d has no creation record in the capture" % (begin_action.eventId, rp_id))
        info = child(sf.chunks[rp.initialisationChunks[0]], "CreateInfo")
        subpasses = children(child(info, "pSubpasses"))
        if len(subpasses) != 1:
            unsupported.append("event %d: render pass with %d subpasses imported as one pass per subpass is not "
                               "supported; all its draws go to one pass" % (begin_action.eventId, len(subpasses)))
        # The images behind the attachments: framebuffer -> image views -> images, so that the
        # same image keeps one name across passes.
        images = []
        fb = resources.get(int(child(begin, "framebuffer").AsResourceId()))
        if fb is not None and fb.initialisationChunks:
            for view in children(child(child(sf.chunks[fb.initialisationChunks[0]], "CreateInfo"), "pAttachments")):
                vr = resources.get(int(view.AsResourceId()))
                img = None
                if vr is not None and vr.initialisationChunks:
                    img = int(child(child(sf.chunks[vr.initialisationChunks[0]], "CreateInfo"), "image").AsResourceId())
                images.append(img)
        atts = []
        for i, ad in enumerate(children(child(info, "pAttachments"))):
            fmt = child(ad, "format").AsString()
            samples = child(ad, "samples").AsString()
            load = enum_tail(child(ad, "loadOp").AsString(), "VK_ATTACHMENT_LOAD_OP_")
            store = enum_tail(child(ad, "storeOp").AsString(), "VK_ATTACHMENT_STORE_OP_")
            if load not in LOAD_OPS or store not in STORE_OPS:
                fail("event %d: attachment %d has load op %s / store op %s, not known" % (begin_action.eventId, i,
                                                                                          load, store))
            att = {"index": i, "vk_format": fmt, "samples": int(enum_tail(samples, "VK_SAMPLE_COUNT_").split("_")[0]),
                   "load": LOAD_OPS[load], "store": STORE_OPS[store]}
            if i < len(clears):
                att["clear"] = clears[i]
            if i < len(images) and images[i] is not None:
                att["image"] = images[i]
            else:
                unsupported.append("event %d: attachment %d's image not found (imageless framebuffer?); named by "
                                   "its pass" % (begin_action.eventId, i))
            atts.append(att)
        return atts

    frame = {"format": "tbdrsim-capture 1", "source": {"tool": "renderdoc", "renderdoc_version": rd.GetVersionString(),
                                                     "api": api, "capture": os.path.basename(rdc_path)},
             "clip_convention": "vulkan", "passes": [], "dispatches": [], "unsupported": unsupported}
    current = None
    final_target = None
    final_event = None
    saved_textures = {}

    def save_texture(rid, path, event):
        """Writes an 8-bit RGBA/BGRA texture's base level as an RGB PNG, read at `event`. (RenderDoc
        1.24's SaveTexture crashes on a swapchain image under lavapipe, so the bytes are read with
        GetTextureData and encoded here.)"""
        c.SetFrameEvent(event, True)
        t = textures[int(rid)]
        f = t.format
        if f.compByteWidth != 1 or f.compCount not in (3, 4) or f.type != rd.ResourceFormatType.Regular:
            unsupported.append("event %d: texture %d of format %s not saved as an image (8-bit RGB(A) only)"
                               % (event, int(rid), f.Name()))
            return False
        data = c.GetTextureData(t.resourceId, rd.Subresource())
        n = f.compCount
        if len(data) < t.width * t.height * n:
            fail("event %d: texture %d returned %d bytes, %dx%dx%d expected" % (event, int(rid), len(data), t.width,
                                                                                 t.height, n))
        rows = []
        for y in range(t.height):
            row = data[y * t.width * n:(y + 1) * t.width * n]
            rgb = bytearray(t.width * 3)
            r, b = (2, 0) if f.BGRAOrder() else (0, 2)
            rgb[0::3] = row[r::n]
            rgb[1::3] = row[1::n]
            rgb[2::3] = row[b::n]
            rows.append(b"\0" + bytes(rgb))
        write_png(path, t.width, t.height, b"".join(rows))
        return True

    for a in actions:
        name = a.GetName(sf)
        if a.flags & rd.ActionFlags.CommandBufferBoundary:
            continue  # vkBeginCommandBuffer / vkEndCommandBuffer markers, not render passes
        if a.flags & rd.ActionFlags.BeginPass:
            if current is not None:
                fail("event %d: %s inside an open render pass" % (a.eventId, name))
            current = {"name": "pass_%d" % a.eventId, "event": a.eventId, "attachments": render_pass_desc(a),
                       "draws": []}
            continue
        if a.flags & rd.ActionFlags.EndPass:
            if current is None:
                fail("event %d: %s without a render pass" % (a.eventId, name))
            frame["passes"].append(current)
            current = None
            continue
        if a.flags & rd.ActionFlags.Dispatch:
            frame["dispatches"].append({"event": a.eventId, "name": name, "groups": list(a.dispatchDimension)})
            unsupported.append("event %d: %s - compute dispatch of the application's own kernel; tbdrsim replays only "
                               "its built-in kernels, so it is listed, not replayed" % (a.eventId, name))
            continue
        if a.flags & (rd.ActionFlags.Clear | rd.ActionFlags.Copy | rd.ActionFlags.Resolve | rd.ActionFlags.GenMips):
            unsupported.append("event %d: %s - transfer/clear command outside a render pass, not simulated"
                               % (a.eventId, name))
            continue
        if not (a.flags & rd.ActionFlags.Drawcall):
            continue
        if current is None:
            fail("event %d: %s outside a render pass" % (a.eventId, name))
        current["draws"].append(export_draw(rd, c, a, name, textures, saved_textures, outdir, unsupported, save_texture))
        # The attachment bound by the draw's pass is the frame's output when it is the last one drawn to.
        ps = c.GetPipelineState()
        targets = [t.resourceId for t in ps.GetOutputTargets() if t.resourceId != rd.ResourceId.Null()]
        if targets:
            final_target, final_event = targets[0], a.eventId
        draw = current["draws"][-1]
        draw["targets"] = [int(t) for t in targets]
        depth = ps.GetDepthTarget().resourceId
        draw["depth_target"] = int(depth) if depth != rd.ResourceId.Null() else None
    if current is not None:
        fail("render pass begun at event %d is not ended in the capture (truncated frame?)" % current["event"])
    if final_target is None:
        fail("%s: no draw writes a colour target; nothing to import" % rdc_path)

    tex = textures[int(final_target)]
    frame["width"], frame["height"] = tex.width, tex.height
    frame["final_target"] = int(final_target)
    # The application's own frame: the final colour target after the last event that draws to it
    # (its pass's store has happened once the pass ends, so the texture is read at the pass end).
    last_event = max(a.eventId for a in actions)
    if save_texture(final_target, os.path.join(outdir, "reference.png"), last_event):
        frame["reference_image"] = "reference.png"

    # Which triangle covers a pixel in the application's frame: RenderDoc's pixel history on a grid of
    # pixels (every pixel would take minutes), the last draw that passed and its primitive id.
    samples = []
    if history_samples > 0:
        c.SetFrameEvent(last_event, True)
        step = max(1, int((tex.width * tex.height / history_samples) ** 0.5))
        for y in range(step // 2, tex.height, step):
            for x in range(step // 2, tex.width, step):
                hist = c.PixelHistory(final_target, x, y, rd.Subresource(), rd.CompType.Typeless)
                hit = None
                for m in hist:
                    if m.Passed() and any(m.eventId == d["event"] for p in frame["passes"] for d in p["draws"]):
                        hit = [m.eventId, m.primitiveID]
                samples.append([x, y] + (hit if hit else [-1, -1]))
        frame["pixel_history"] = {"step": step, "samples": samples}
    return frame


def export_draw(rd, c, a, name, textures, saved_textures, outdir, unsupported, save_texture):
    c.SetFrameEvent(a.eventId, True)
    where = "event %d (%s)" % (a.eventId, name)
    vk = c.GetVulkanPipelineState()
    ps = c.GetPipelineState()
    draw = {"event": a.eventId, "name": name}
    if a.numInstances > 1:
        unsupported.append("%s: %d instances; only instance 0's geometry is imported" % (where, a.numInstances))
    topo = {rd.Topology.TriangleList: "TriangleList", rd.Topology.TriangleStrip: "TriangleStrip",
            rd.Topology.TriangleFan: "TriangleFan"}.get(ps.GetPrimitiveTopology(), str(ps.GetPrimitiveTopology()))
    if topo not in ("TriangleList", "TriangleStrip", "TriangleFan"):
        fail("%s: topology %s is not imported (triangles only)" % (where, topo))

    # Viewport and scissor: the simulator has one viewport, the frame; the importer maps each draw's
    # clip positions through its own viewport so every vertex lands on the same pixel and depth.
    vps = vk.viewportScissor.viewportScissors
    if not vps:
        fail("%s: no viewport bound" % where)
    vp, sc = vps[0].vp, vps[0].scissor
    draw["viewport"] = [vp.x, vp.y, vp.width, vp.height, vp.minDepth, vp.maxDepth]
    draw["scissor"] = [sc.x, sc.y, sc.width, sc.height]
    if len(vps) > 1:
        unsupported.append("%s: %d viewports; only the first is imported" % (where, len(vps)))
    ds = vk.depthStencil
    draw["depth_test"] = bool(ds.depthTestEnable)
    draw["depth_write"] = bool(ds.depthTestEnable and ds.depthWriteEnable)
    draw["depth_compare"] = {getattr(rd.CompareFunction, k): v for k, v in COMPARE.items()}.get(ds.depthFunction)
    if draw["depth_compare"] is None:
        fail("%s: depth compare %s not known" % (where, ds.depthFunction))
    if ds.stencilTestEnable:
        unsupported.append("%s: stencil test enabled; imported without it" % where)
    cull = vk.rasterizer.cullMode
    draw["cull"] = {rd.CullMode.NoCull: "none", rd.CullMode.Back: "back", rd.CullMode.Front: "front"}.get(cull)
    if draw["cull"] is None:
        unsupported.append("%s: cull mode %s (front and back) imported as none" % (where, cull))
        draw["cull"] = "none"
    draw["front_face"] = "ccw" if vk.rasterizer.frontCCW else "cw"
    blends = vk.colorBlend.blends
    draw["blend"] = "off"
    if blends and blends[0].enabled:
        b = blends[0].colorBlend
        src, dst = b.source.name, b.destination.name
        if src == "SrcAlpha" and dst == "InvSrcAlpha":
            draw["blend"] = "alpha"
        elif src == "One" and dst == "One":
            draw["blend"] = "add"
        else:
            unsupported.append("%s: blend %s/%s imported as alpha blending" % (where, src, dst))
            draw["blend"] = "alpha"

    # Fragment shader: static SPIR-V cost.
    fs = ps.GetShaderReflection(rd.ShaderStage.Fragment)
    if fs is None:
        draw["shader"] = {"alu_ops": 0, "tex_fetches": 0, "varyings": 0, "color_outputs": 0, "discard": False,
                          "source": "no fragment shader"}
    else:
        try:
            cost = spirv_cost.shader_cost(bytes(fs.rawBytes))
        except spirv_cost.SpirvError as e:
            fail("%s: fragment shader: %s" % (where, e))
        if cost["loops"]:
            unsupported.append("%s: fragment shader has %d loop(s); each body is counted once (static count)"
                               % (where, cost["loops"]))
        varyings = sum(s.compCount for s in fs.inputSignature if s.systemValue == rd.ShaderBuiltin.Undefined)
        outputs = sum(1 for s in fs.outputSignature if s.systemValue == rd.ShaderBuiltin.ColorOutput)
        draw["shader"] = {"alu_ops": cost["alu_ops"], "tex_fetches": cost["tex_fetches"], "varyings": varyings,
                          "color_outputs": outputs, "discard": cost["discard"], "loads": cost["loads"],
                          "stores": cost["stores"], "branches": cost["branches"], "loops": cost["loops"],
                          "source": "spirv static count, %d instructions" % cost["instructions"],
                          "entry": fs.entryPoint, "shader_id": int(fs.resourceId)}
    # Sampled textures the fragment shader binds.
    bound = []
    for used in ps.GetReadOnlyResources(rd.ShaderStage.Fragment):
        for res in used.resources:
            rid = int(res.resourceId)
            if rid in textures and rid not in bound:
                bound.append(rid)
    draw["textures"] = []
    for rid in bound:
        t = textures[rid]
        fname = "tex_%d.png" % rid
        if rid not in saved_textures:
            saved_textures[rid] = fname if save_texture(rid, os.path.join(outdir, fname), a.eventId) else None
            c.SetFrameEvent(a.eventId, True)
        entry = {"id": rid, "width": t.width, "height": t.height, "format": t.format.Name(), "mips": t.mips}
        if saved_textures[rid]:
            entry["file"] = saved_textures[rid]
        draw["textures"].append(entry)
    # Post-vertex-shader positions (RenderDoc's VS output: gl_Position first in each vertex).
    m = c.GetPostVSData(0, 0, rd.MeshDataStage.VSOut)
    if m.vertexResourceId == rd.ResourceId.Null() or m.numIndices == 0:
        fail("%s: RenderDoc has no vertex shader output for it" % where)
    vs = ps.GetShaderReflection(rd.ShaderStage.Vertex)
    count = m.numIndices
    if m.indexResourceId != rd.ResourceId.Null() and m.indexByteStride:
        idx_bytes = c.GetBufferData(m.indexResourceId, m.indexByteOffset, count * m.indexByteStride)
        fmt = {1: "B", 2: "H", 4: "I"}[m.indexByteStride]
        indices = list(struct.unpack("<%d%s" % (count, fmt), idx_bytes[:count * m.indexByteStride]))
        nverts = max(indices) + 1
    else:
        indices = None
        nverts = count
    data = c.GetBufferData(m.vertexResourceId, m.vertexByteOffset, nverts * m.vertexByteStride)
    if len(data) < nverts * m.vertexByteStride:
        fail("%s: vertex shader output is %d bytes, %d vertices of %d bytes expected" % (where, len(data), nverts,
                                                                                         m.vertexByteStride))
    clip = []
    for v in range(nverts):
        clip.append(list(struct.unpack_from("<4f", data, v * m.vertexByteStride)))
    draw["clip_positions"] = clip
    if indices is not None:
        draw["indices"] = indices
    draw["topology"] = {"TriangleList": "triangles", "TriangleStrip": "triangle_strip",
                        "TriangleFan": "triangle_fan"}[topo]
    draw["vertex_stride_bytes"] = m.vertexByteStride
    # Texture coordinates for the base colour: with exactly one sampled texture, the first
    # non-builtin vertex output of 2+ components (a heuristic: SPIR-V does not say which output
    # feeds the sampler without data-flow analysis). Outputs are packed in signature order, 4 bytes
    # a component, after gl_Position.
    if len(bound) == 1:
        offset = 0
        for s in vs.outputSignature:
            if s.systemValue == rd.ShaderBuiltin.Position:
                offset += 16
                continue
            if s.systemValue == rd.ShaderBuiltin.Undefined and s.compCount >= 2 and offset + 8 <= m.vertexByteStride:
                draw["uvs"] = [list(struct.unpack_from("<2f", data, v * m.vertexByteStride + offset))
                               for v in range(nverts)]
                draw["uv_source"] = "vertex output '%s' (heuristic: first non-builtin output)" % s.varName
                break
            offset += 4 * s.compCount
    return draw


def write_png(path, width, height, filtered_rows):
    """An 8-bit RGB PNG from rows that already carry their filter byte (PNG spec, 11.2 and 12.7)."""
    import zlib

    def chunk(tag, body):
        return struct.pack(">I", len(body)) + tag + body + struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(filtered_rows, 6)) + chunk(b"IEND", b""))


def main(argv):
    import argparse
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n")[0])
    ap.add_argument("capture")
    ap.add_argument("outdir")
    ap.add_argument("--history-samples", type=int, default=1200,
                    help="pixels whose triangle RenderDoc's pixel history reads (0: none)")
    args = ap.parse_args(argv)
    try:
        import renderdoc  # noqa: F401
    except ImportError:
        print("%s: python3-renderdoc is not installed (scripts/install_capture_deps.sh)" % PROG, file=sys.stderr)
        return 2
    os.makedirs(args.outdir, exist_ok=True)
    # Everything goes to a scratch folder first: nothing is written on error.
    with tempfile.TemporaryDirectory(dir=args.outdir) as tmp:
        try:
            frame = export(args.capture, tmp, args.history_samples)
        except ExportError as e:
            print("%s: %s" % (PROG, e), file=sys.stderr)
            return 2
        with open(os.path.join(tmp, "frame.json"), "w") as f:
            json.dump(frame, f, separators=(",", ":"))
        for name in os.listdir(tmp):
            os.replace(os.path.join(tmp, name), os.path.join(args.outdir, name))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
