"""Transfers (copies, blits, resolves, clears, fills, updates) and compute dispatches of a Vulkan
capture for rdc_export.py, with the bytes each moves computed from its recorded regions.

Bytes are texel bytes x region extent x layers (block-compressed images by 4x4 blocks); a resolve
reads every sample; a clear reads nothing; fill/update write their size. The call's arguments are
read from RenderDoc's structured data (1.24 names: vkCmdBlitImage's `destImage`, the *2 variants'
VkBlitImageInfo2 etc. with `dstImage`).
"""

import spirv_cost
from export_images import texel_bytes
from export_sd import child, children, enum_tail, fail, first_child

WHOLE = 0xFFFFFFFF
WHOLE_SIZE = 0xFFFFFFFFFFFFFFFF
# Recorded call (without the KHR suffix and the 2 of the *2 variants) -> the contract's kind.
KINDS = {"vkCmdBlitImage": "blit", "vkCmdCopyImage": "copy_image", "vkCmdCopyBuffer": "copy_buffer",
         "vkCmdCopyBufferToImage": "copy_buffer_to_image", "vkCmdCopyImageToBuffer": "copy_image_to_buffer",
         "vkCmdResolveImage": "resolve", "vkCmdClearColorImage": "clear_color_image",
         "vkCmdClearDepthStencilImage": "clear_depth_stencil_image", "vkCmdFillBuffer": "fill_buffer",
         "vkCmdUpdateBuffer": "update_buffer"}


def call_kind(chunk_name):
    """The contract's transfer kind of a recorded call name, or None."""
    base = chunk_name[:-3] if chunk_name.endswith("KHR") else chunk_name
    base = base[:-1] if base.endswith("2") else base
    return KINDS.get(base)


class TransferReader:
    """Builds `transfers` and `dispatches` entries."""

    def __init__(self, rd, c, sf, records, textures, buffers, unsupported):
        self.rd = rd
        self.c = c
        self.sf = sf
        self.records = records
        self.textures = textures
        self.buffers = buffers
        self.unsupported = unsupported

    # -- transfers -----------------------------------------------------------------------------

    def export(self, a, name):
        """The `transfers` entry of a Copy/Resolve/Clear/GenMips action outside a render pass, or
        None (listed as unsupported) when its call is not one the exporter reads."""
        where = "transfer at event %d (%s)" % (a.eventId, name)
        for ev in a.events:
            if ev.chunkIndex >= len(self.sf.chunks):
                continue
            ch = self.sf.chunks[ev.chunkIndex]
            kind = call_kind(ch.name)
            if kind is not None:
                return self.transfer(ch, kind, a, name, where)
        self.unsupported.append("%s: %s not read (its call is none of %s)" % (where, name, ", ".join(sorted(KINDS))))
        return None

    def transfer(self, ch, kind, a, name, where):
        """One transfer entry from its recorded call."""
        params = ch if ch.FindChild("pRegions") is not None or ch.FindChild("pRanges") is not None else None
        if params is None:
            params = next((x for x in children(ch) if x.FindChild("pRegions") is not None), ch)
        t = {"event": a.eventId, "name": name, "kind": kind, "read_bytes": 0, "write_bytes": 0,
             "src_image": None, "dst_image": None}
        getattr(self, "_" + kind)(params, t, where)
        return t

    def image_info(self, obj, member_names, t, side):
        """Records src_/dst_image and its format; returns the image's TextureDescription."""
        rid = int(first_child(obj, *member_names).AsResourceId())
        t[side + "_image"] = rid
        fmt = self.records.image_format(rid)
        if fmt is not None:
            t[side + "_format"] = fmt
        tex = self.textures.get(rid)
        if tex is None:
            fail("transfer at event %d: image %d is not a texture RenderDoc knows" % (t["event"], rid))
        return tex

    def region_bytes(self, tex, w, h, d, layers):
        """Bytes of a w x h x d region of `layers` layers of an image (by blocks when compressed)."""
        size, block = texel_bytes(self.rd, tex.format)
        bw, bh = (w + block - 1) // block, (h + block - 1) // block
        return size * bw * bh * max(1, d) * max(1, layers)

    @staticmethod
    def extent3(e):
        """(w, h, d) of a VkExtent3D."""
        return child(e, "width").AsInt(), child(e, "height").AsInt(), child(e, "depth").AsInt()

    @staticmethod
    def layers(sub, tex):
        """Layer count of a VkImageSubresourceLayers (VK_REMAINING_ARRAY_LAYERS resolved)."""
        n = child(sub, "layerCount").AsInt()
        return tex.arraysize - child(sub, "baseArrayLayer").AsInt() if n == WHOLE else n

    def _blit(self, p, t, where):
        src = self.image_info(p, ("srcImage",), t, "src")
        dst = self.image_info(p, ("dstImage", "destImage"), t, "dst")
        regions = children(child(p, "pRegions"))
        for i, r in enumerate(regions):
            se = _offsets_extent(child(r, "srcOffsets"))
            de = _offsets_extent(child(r, "dstOffsets"))
            t["read_bytes"] += self.region_bytes(src, *se, self.layers(child(r, "srcSubresource"), src))
            t["write_bytes"] += self.region_bytes(dst, *de, self.layers(child(r, "dstSubresource"), dst))
            if i == 0:
                t["src_extent"], t["dst_extent"] = list(se[:2]), list(de[:2])
                t["src_mip"] = child(child(r, "srcSubresource"), "mipLevel").AsInt()
                t["dst_mip"] = child(child(r, "dstSubresource"), "mipLevel").AsInt()
        t["regions"] = len(regions)
        t["filter"] = enum_tail(child(p, "filter").AsString(), "VK_FILTER_")

    def _copy_image(self, p, t, where, resolve=False):
        src = self.image_info(p, ("srcImage",), t, "src")
        dst = self.image_info(p, ("dstImage", "destImage"), t, "dst")
        regions = children(child(p, "pRegions"))
        for i, r in enumerate(regions):
            w, h, d = self.extent3(child(r, "extent"))
            nbytes = self.region_bytes(src, w, h, d, self.layers(child(r, "srcSubresource"), src))
            t["read_bytes"] += nbytes * (max(1, src.msSamp) if resolve else 1)
            t["write_bytes"] += self.region_bytes(dst, w, h, d, self.layers(child(r, "dstSubresource"), dst))
            if i == 0:
                t["src_extent"] = t["dst_extent"] = [w, h]
        t["regions"] = len(regions)

    def _resolve(self, p, t, where):
        self._copy_image(p, t, where, resolve=True)

    def _copy_buffer(self, p, t, where):
        t["src_buffer"] = int(first_child(p, "srcBuffer").AsResourceId())
        t["dst_buffer"] = int(first_child(p, "dstBuffer", "destBuffer").AsResourceId())
        for r in children(child(p, "pRegions")):
            t["read_bytes"] += child(r, "size").AsInt()
        t["write_bytes"] = t["read_bytes"]

    def _buffer_image(self, p, t, to_image):
        side = "dst" if to_image else "src"
        names = ("dstImage", "destImage") if to_image else ("srcImage",)
        tex = self.image_info(p, names, t, side)
        buf = first_child(p, *(("srcBuffer",) if to_image else ("dstBuffer", "destBuffer")))
        t[("src" if to_image else "dst") + "_buffer"] = int(buf.AsResourceId())
        regions = children(child(p, "pRegions"))
        for i, r in enumerate(regions):
            w, h, d = self.extent3(child(r, "imageExtent"))
            nbytes = self.region_bytes(tex, w, h, d, self.layers(child(r, "imageSubresource"), tex))
            t["read_bytes"] += nbytes
            t["write_bytes"] += nbytes
            if i == 0:
                t[side + "_extent"] = [w, h]
                t[side + "_mip"] = child(child(r, "imageSubresource"), "mipLevel").AsInt()
        t["regions"] = len(regions)

    def _copy_buffer_to_image(self, p, t, where):
        self._buffer_image(p, t, to_image=True)

    def _copy_image_to_buffer(self, p, t, where):
        self._buffer_image(p, t, to_image=False)

    def _clear_image(self, p, t, where):
        tex = self.image_info(p, ("image",), t, "dst")
        for r in children(child(p, "pRanges")):
            base_mip, mips = child(r, "baseMipLevel").AsInt(), child(r, "levelCount").AsInt()
            base_layer, layers = child(r, "baseArrayLayer").AsInt(), child(r, "layerCount").AsInt()
            mips = tex.mips - base_mip if mips == WHOLE else mips
            layers = tex.arraysize - base_layer if layers == WHOLE else layers
            for m in range(base_mip, base_mip + mips):
                t["write_bytes"] += self.region_bytes(tex, max(1, tex.width >> m), max(1, tex.height >> m),
                                                      max(1, tex.depth >> m), layers)
        t["dst_extent"] = [tex.width, tex.height]

    _clear_color_image = _clear_image
    _clear_depth_stencil_image = _clear_image

    def _fill_buffer(self, p, t, where):
        buf = int(first_child(p, "dstBuffer", "destBuffer").AsResourceId())
        t["dst_buffer"] = buf
        size = child(p, "fillSize").AsInt() if p.FindChild("fillSize") is not None else child(p, "size").AsInt()
        if size in (WHOLE_SIZE, -1):
            offset = first_child(p, "destOffset", "dstOffset").AsInt()
            size = self.buffers[buf].length - offset if buf in self.buffers else 0
        t["write_bytes"] = size

    def _update_buffer(self, p, t, where):
        t["dst_buffer"] = int(first_child(p, "dstBuffer", "destBuffer").AsResourceId())
        t["write_bytes"] = child(p, "dataSize").AsInt()

    # -- dispatches ----------------------------------------------------------------------------

    def dispatch(self, a, name):
        """The `dispatches` entry: groups, local size, the compute shader's static SPIR-V cost and the
        sizes of the resources it binds."""
        rd, c = self.rd, self.c
        where = "dispatch at event %d (%s)" % (a.eventId, name)
        c.SetFrameEvent(a.eventId, True)
        ps = c.GetPipelineState()
        d = {"event": a.eventId, "name": name, "groups": list(a.dispatchDimension)}
        cs = ps.GetShaderReflection(rd.ShaderStage.Compute)
        if cs is None:
            fail("%s: no compute shader bound" % where)
        d["local_size"] = list(cs.dispatchThreadsDimension)
        try:
            cost = spirv_cost.shader_cost(bytes(cs.rawBytes))
        except spirv_cost.SpirvError as e:
            fail("%s: compute shader: %s" % (where, e))
        d["shader"] = {k: cost[k] for k in ("alu_ops", "tex_fetches", "loads", "stores", "branches", "loops",
                                            "instructions")}
        d["shader"]["source"] = "spirv static count, %d instructions" % cost["instructions"]
        ro = self.bound_bytes(ps.GetReadOnlyResources(rd.ShaderStage.Compute))
        rw = self.bound_bytes(ps.GetReadWriteResources(rd.ShaderStage.Compute))
        if ro is not None and rw is not None:
            d["reads_bytes"], d["writes_bytes"] = ro + rw, rw
            d["bytes_source"] = "whole sizes of the bound resources (read-only + read-write; read-write)"
        return d

    def bound_bytes(self, used_list):
        """Sum of the byte sizes of bound buffers and images, or None when one is unknown."""
        total = 0
        for used in used_list:
            for res in used.resources:
                rid = int(res.resourceId)
                if rid == 0:
                    continue
                if rid in self.buffers:
                    total += self.buffers[rid].length
                elif rid in self.textures:
                    total += self.textures[rid].byteSize
                else:
                    return None
        return total


def _offsets_extent(offsets):
    """(w, h, d) spanned by a blit region's two VkOffset3D."""
    o = [[child(x, k).AsInt() for k in ("x", "y", "z")] for x in children(offsets)]
    return abs(o[1][0] - o[0][0]), abs(o[1][1] - o[0][1]), max(1, abs(o[1][2] - o[0][2]))
