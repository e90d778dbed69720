"""Render passes of a Vulkan capture for rdc_export.py: attachments, load/store ops, clears, sizes.

Three ways a pass begins, each read from the recorded call (RenderDoc's structured data):
- vkCmdBeginRenderPass / vkCmdBeginRenderPass2: VkRenderPassBeginInfo -> the render pass's
  vkCreateRenderPass(2) record (attachment formats, samples, load/store, subpass resolve
  attachments) and the framebuffer's views, or for an imageless framebuffer the views of
  VkRenderPassAttachmentBeginInfo in the begin info's pNext;
- vkCmdBeginRendering (dynamic rendering, what zink records): VkRenderingInfo's colour, depth and
  stencil VkRenderingAttachmentInfo, each view -> its image (format and samples of the image).
Every view is followed to its VkImage so that one image keeps one name across passes.
"""

from export_sd import child, children, enum_tail, fail, find_in_chain, flag_names, is_null

LOAD_OPS = {"clear": "clear", "load": "load", "dont_care": "dont_care", "none_ext": "dont_care",
            "none_khr": "dont_care", "none": "dont_care"}
STORE_OPS = {"store": "store", "dont_care": "dont_care", "none": "dont_care", "none_khr": "dont_care",
             "none_ext": "dont_care", "none_qcom": "dont_care"}
BEGIN_CHUNKS = ("vkCmdBeginRenderPass", "vkCmdBeginRenderPass2", "vkCmdBeginRenderPass2KHR",
                "vkCmdBeginRendering", "vkCmdBeginRenderingKHR")


class PassReader:
    """Describes the render pass begun by an action (ActionFlags.BeginPass)."""

    def __init__(self, rd, sf, records, textures, unsupported):
        self.rd = rd
        self.sf = sf
        self.records = records
        self.textures = textures
        self.unsupported = unsupported

    def begin_chunk(self, action):
        """The vkCmdBeginRenderPass(2)/vkCmdBeginRendering chunk of a BeginPass action, or None."""
        for ev in action.events:
            ch = self.sf.chunks[ev.chunkIndex] if ev.chunkIndex < len(self.sf.chunks) else None
            if ch is not None and ch.name in BEGIN_CHUNKS:
                return ch
        return None

    def describe(self, action):
        """The pass entry (without draws) of frame.json for a BeginPass action."""
        where = "pass at event %d (%s)" % (action.eventId, action.GetName(self.sf))
        ch = self.begin_chunk(action)
        if ch is None:
            fail("%s: begun by none of the calls the exporter reads (%s)" % (where, ", ".join(BEGIN_CHUNKS)))
        begin = ch.name.replace("KHR", "")
        if begin == "vkCmdBeginRendering":
            p = self.dynamic_rendering(child(ch, "pRenderingInfo"), where)
        else:
            p = self.render_pass(child(ch, "RenderPassBegin"), where)
        p.update({"name": "pass_%d" % action.eventId, "event": action.eventId, "begin": begin, "draws": []})
        return p

    # -- shared --------------------------------------------------------------------------------

    def image_size(self, image, mip):
        """(width, height) of an image at a mip level, or (None, None) when the image is unknown."""
        t = self.textures.get(image) if image is not None else None
        if t is None:
            return None, None
        return max(1, t.width >> mip), max(1, t.height >> mip)

    def view_format(self, view_id, image):
        """(VK_FORMAT_..., samples) of an attachment: the view's format (what is rendered; a swapchain
        image has no vkCreateImage record) and the image's sample count."""
        info = self.records.create_info(view_id, "image view")
        fmt = child(info, "format").AsString() if info is not None else None
        t = self.textures.get(image) if image is not None else None
        return fmt, (max(1, t.msSamp) if t is not None else None)

    def attach_image(self, att, view_id, where, index):
        """Sets an attachment's image, width and height from an image view."""
        image, mip = self.records.view_image(view_id)
        if image is None:
            self.unsupported.append("%s attachment %d: image view %d has no creation record; the attachment is "
                                    "named by its pass" % (where, index, view_id))
            return
        att["image"] = image
        att["width"], att["height"] = self.image_size(image, mip)
        if mip:
            att["mip"] = mip

    @staticmethod
    def ops(load, store, where, index):
        """The contract's load/store names of Vulkan load/store op strings; fails on unknown ones."""
        lo = enum_tail(load, "VK_ATTACHMENT_LOAD_OP_")
        st = enum_tail(store, "VK_ATTACHMENT_STORE_OP_")
        if lo not in LOAD_OPS or st not in STORE_OPS:
            fail("%s attachment %d: load op %s / store op %s, not known" % (where, index, load, store))
        return LOAD_OPS[lo], STORE_OPS[st]

    @staticmethod
    def clear_value(cv):
        """{"color", "depth", "stencil"} of a VkClearValue (the union read both ways, as in format 1)."""
        col = [f.AsFloat() for f in children(child(child(cv, "color"), "float32"))]
        ds = child(cv, "depthStencil")
        return {"color": col, "depth": child(ds, "depth").AsFloat(), "stencil": child(ds, "stencil").AsInt()}

    @staticmethod
    def rect(r):
        """[x, y, width, height] of a VkRect2D."""
        off, ext = child(r, "offset"), child(r, "extent")
        return [child(off, "x").AsInt(), child(off, "y").AsInt(), child(ext, "width").AsInt(),
                child(ext, "height").AsInt()]

    # -- vkCmdBeginRenderPass(2) -------------------------------------------------------------------

    def render_pass(self, begin, where):
        """Pass fields of a VkRenderPassBeginInfo and its render pass's creation record."""
        rp_id = int(child(begin, "renderPass").AsResourceId())
        info = self.records.create_info(rp_id, "render pass")
        if info is None:
            fail("%s: render pass %d has no creation record in the capture" % (where, rp_id))
        clears = [self.clear_value(cv) for cv in children(child(begin, "pClearValues"))]
        views = self.framebuffer_views(begin, where)
        subpasses = children(child(info, "pSubpasses"))
        if len(subpasses) != 1:
            self.unsupported.append("%s: render pass with %d subpasses; all its draws go to one pass"
                                    % (where, len(subpasses)))
        self.refuse_multiview(info, subpasses, where)
        atts = []
        for i, ad in enumerate(children(child(info, "pAttachments"))):
            load, store = self.ops(child(ad, "loadOp").AsString(), child(ad, "storeOp").AsString(), where, i)
            att = {"index": i, "vk_format": child(ad, "format").AsString(),
                   "samples": int(enum_tail(child(ad, "samples").AsString(), "VK_SAMPLE_COUNT_").split("_")[0]),
                   "load": load, "store": store}
            self.stencil_ops(att, ad)
            if i < len(clears):
                att["clear"] = clears[i]
            if i < len(views) and views[i] is not None:
                self.attach_image(att, views[i], where, i)
            else:
                self.unsupported.append("%s attachment %d: its image view is not recorded; named by its pass"
                                        % (where, i))
            atts.append(att)
        self.mark_subpass_resolves(atts, subpasses)
        return {"render_area": self.rect(child(begin, "renderArea")), "attachments": atts}

    def stencil_ops(self, att, ad):
        """Adds stencil_load/stencil_store to a depth-stencil attachment description."""
        fmt = att["vk_format"]
        if "_S8_" in fmt + "_" or fmt.endswith("S8_UINT"):
            sl = enum_tail(child(ad, "stencilLoadOp").AsString(), "VK_ATTACHMENT_LOAD_OP_")
            ss = enum_tail(child(ad, "stencilStoreOp").AsString(), "VK_ATTACHMENT_STORE_OP_")
            att["stencil_load"], att["stencil_store"] = LOAD_OPS.get(sl, sl), STORE_OPS.get(ss, ss)

    def framebuffer_views(self, begin, where):
        """The image views of a begin info: the framebuffer's pAttachments, or for an imageless
        framebuffer those of VkRenderPassAttachmentBeginInfo in the begin info's pNext."""
        imageless = find_in_chain(begin, "VkRenderPassAttachmentBeginInfo")
        if imageless is not None:
            return [int(v.AsResourceId()) for v in children(child(imageless, "pAttachments"))]
        fb_info = self.records.create_info(int(child(begin, "framebuffer").AsResourceId()), "framebuffer")
        if fb_info is None or fb_info.FindChild("pAttachments") is None:
            return []
        return [int(v.AsResourceId()) for v in children(child(fb_info, "pAttachments"))]

    def refuse_multiview(self, info, subpasses, where):
        """Multiview renders each draw once per view with its own clip positions: not expressible."""
        mv = find_in_chain(info, "VkRenderPassMultiviewCreateInfo")
        masks = [child(mv, "pViewMasks")] if mv is not None else []
        views = [m.AsInt() for arr in masks for m in children(arr)]
        views += [s.FindChild("viewMask").AsInt() for s in subpasses if s.FindChild("viewMask") is not None]
        if any(views):
            fail("%s: multiview (view masks %s): each view has its own clip positions, which the intermediate "
                 "cannot express" % (where, views))

    @staticmethod
    def mark_subpass_resolves(atts, subpasses):
        """resolve_of on the attachments a subpass resolves into (colour, and depth-stencil via
        VkSubpassDescriptionDepthStencilResolve)."""
        unused = 0xFFFFFFFF
        for sp in subpasses:
            colours = [child(r, "attachment").AsInt() for r in children(child(sp, "pColorAttachments"))]
            resolves = sp.FindChild("pResolveAttachments")
            for src, r in zip(colours, children(resolves) if resolves is not None else []):
                dst = child(r, "attachment").AsInt()
                if dst != unused and src != unused and dst < len(atts):
                    atts[dst]["resolve_of"] = src
            dsr = find_in_chain(sp, "VkSubpassDescriptionDepthStencilResolve")
            ds = sp.FindChild("pDepthStencilAttachment")
            if dsr is not None and not is_null(ds):
                target = dsr.FindChild("pDepthStencilResolveAttachment")
                if not is_null(target):
                    dst = child(target, "attachment").AsInt()
                    if dst != unused and dst < len(atts):
                        atts[dst]["resolve_of"] = child(ds, "attachment").AsInt()
                        atts[dst]["resolve_mode"] = enum_tail(child(dsr, "depthResolveMode").AsString(),
                                                              "VK_RESOLVE_MODE_")

    # -- vkCmdBeginRendering -----------------------------------------------------------------------

    def dynamic_rendering(self, info, where):
        """Pass fields of a VkRenderingInfo: colour attachments in order, then depth, then stencil
        (when a different image), then the resolve targets."""
        view_mask = info.FindChild("viewMask")
        if view_mask is not None and view_mask.AsInt():
            fail("%s: multiview (viewMask 0x%x): each view has its own clip positions, which the intermediate "
                 "cannot express" % (where, view_mask.AsInt()))
        layers = info.FindChild("layerCount")
        if layers is not None and layers.AsInt() > 1:
            self.unsupported.append("%s: %d layers rendered; imported as one" % (where, layers.AsInt()))
        atts, resolves = [], []
        for ai in children(child(info, "pColorAttachments")):
            self.rendering_attachment(ai, atts, resolves, where, depth=False)
        depth = info.FindChild("pDepthAttachment")
        stencil = info.FindChild("pStencilAttachment")
        depth_att = None
        if not is_null(depth) and int(child(depth, "imageView").AsResourceId()) != 0:
            depth_att = self.rendering_attachment(depth, atts, resolves, where, depth=True)
        if not is_null(stencil) and int(child(stencil, "imageView").AsResourceId()) != 0:
            self.stencil_attachment(stencil, depth_att, atts, resolves, where)
        for src, ai, mode in resolves:
            att = {"index": len(atts), "samples": 1, "load": "dont_care", "store": "store", "resolve_of": src,
                   "resolve_mode": mode}
            view = int(child(ai, "resolveImageView").AsResourceId())
            self.attach_image(att, view, where, att["index"])
            att["vk_format"] = self.view_format(view, att.get("image"))[0]
            atts.append(att)
        out = {"render_area": self.rect(child(info, "renderArea")), "attachments": atts}
        flags = flag_names(info.FindChild("flags"), "VK_RENDERING_")
        if flags:
            out["flags"] = flags
        return out

    def rendering_attachment(self, ai, atts, resolves, where, depth):
        """Appends the attachment of one VkRenderingAttachmentInfo (and queues its resolve target)."""
        index = len(atts)
        view = int(child(ai, "imageView").AsResourceId())
        load, store = self.ops(child(ai, "loadOp").AsString(), child(ai, "storeOp").AsString(), where, index)
        att = {"index": index, "load": load, "store": store, "clear": self.clear_value(child(ai, "clearValue"))}
        if view == 0:
            att.update({"vk_format": "VK_FORMAT_UNDEFINED", "samples": 1, "unused": True})
            atts.append(att)
            return att
        self.attach_image(att, view, where, index)
        att["vk_format"], att["samples"] = self.view_format(view, att.get("image"))
        if att["vk_format"] is None or att["samples"] is None:
            fail("%s attachment %d: image view %d or its image has no record in the capture (format or samples "
                 "unknown)" % (where, index, view))
        if depth:
            att["aspect"] = "depth"
        mode = enum_tail(child(ai, "resolveMode").AsString(), "VK_RESOLVE_MODE_")
        if mode not in ("none", "0") and int(child(ai, "resolveImageView").AsResourceId()) != 0:
            resolves.append((index, ai, mode.replace("_bit", "")))
        atts.append(att)
        return att

    def stencil_attachment(self, ai, depth_att, atts, resolves, where):
        """The stencil VkRenderingAttachmentInfo: merged into the depth attachment when it is the same
        image (stencil_load/stencil_store), else an attachment of its own."""
        image, _ = self.records.view_image(int(child(ai, "imageView").AsResourceId()))
        if depth_att is not None and image is not None and depth_att.get("image") == image:
            load, store = self.ops(child(ai, "loadOp").AsString(), child(ai, "storeOp").AsString(), where,
                                   depth_att["index"])
            depth_att["stencil_load"], depth_att["stencil_store"] = load, store
            depth_att["aspect"] = "depth_stencil"
            return
        att = self.rendering_attachment(ai, atts, resolves, where, depth=False)
        att["aspect"] = "stencil"
