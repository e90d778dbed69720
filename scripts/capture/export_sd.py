"""Reading RenderDoc's structured data (the capture's recorded API calls) for rdc_export.py.

RenderDoc keeps every serialised call as an SDChunk, a tree of SDObjects named as in its
serialisation code (renderdoc/driver/vulkan/vk_serialise.cpp and wrappers/*.cpp of the 1.24 tag:
e.g. vkCmdBlitImage's destination image is `destImage`, VkRenderingInfo's members are the Vulkan
names). These helpers find members by name and follow resources to their creation records
(image view -> image, image -> VkImageCreateInfo), so the exporter's code says what it reads.
"""


class ExportError(Exception):
    """A capture that cannot be exported; the message names the event or resource."""


def fail(msg):
    """Raises ExportError(msg): one line naming the event or resource at fault."""
    raise ExportError(msg)


def enum_tail(s, prefix):
    """VK_ATTACHMENT_LOAD_OP_CLEAR -> clear."""
    return s[len(prefix):].lower() if s.startswith(prefix) else s.lower()


def child(obj, name):
    """The member `name` of an SDObject; fails naming both when it is missing."""
    c = obj.FindChild(name)
    if c is None:
        fail("capture structure: %s has no member '%s'" % (obj.name, name))
    return c


def children(obj):
    """The members (or array elements) of an SDObject, in order."""
    return [obj.GetChild(i) for i in range(obj.NumChildren())]


def first_child(obj, *names):
    """The first of several alternative member names present (e.g. dstImage / destImage)."""
    for n in names:
        c = obj.FindChild(n)
        if c is not None:
            return c
    fail("capture structure: %s has none of the members %s" % (obj.name, ", ".join(names)))


def is_null(obj):
    """True for an absent optional struct pointer (SERIALISE_MEMBER_OPT writes no members)."""
    return obj is None or obj.NumChildren() == 0


def pnext_chain(obj):
    """The structures chained in `pNext` of a Vulkan struct (each an SDObject with sType first)."""
    out = []
    nxt = obj.FindChild("pNext") if obj is not None else None
    while nxt is not None and nxt.NumChildren() > 0:
        out.append(nxt)
        nxt = nxt.FindChild("pNext")
    return out


def find_in_chain(obj, type_name):
    """The pNext structure of Vulkan type `type_name` (e.g. VkRenderPassAttachmentBeginInfo), or None."""
    for s in pnext_chain(obj):
        if s.type.name == type_name:
            return s
    return None


def flag_names(obj, prefix):
    """A VkFlags member's set bits as lower-case names: VK_RENDERING_SUSPENDING_BIT -> suspending.
    RenderDoc stringises flags as 'A | B' (0 as 'VkRenderingFlagBits(0)'); 0 gives []."""
    if obj is None or obj.AsInt() == 0:
        return []
    s = obj.AsString()
    names = []
    for part in s.split("|"):
        part = part.strip()
        if part and part != "0":
            names.append(enum_tail(part, prefix).replace("_bit_khr", "").replace("_bit", ""))
    return names


class Records:
    """Creation records of the capture's resources (what vkCreate* was called with)."""

    def __init__(self, sf, resources):
        self.sf = sf
        self.resources = resources

    def create_info(self, rid, what=""):
        """The CreateInfo SDObject of resource `rid`'s first initialisation chunk (`what` names the
        kind of resource for the reader), or None."""
        r = self.resources.get(int(rid))
        if r is None or not r.initialisationChunks:
            return None
        ch = self.sf.chunks[r.initialisationChunks[0]]
        return ch.FindChild("CreateInfo")

    def view_image(self, view_id):
        """(image id, base mip level) behind an image view, or (None, 0) when not recorded."""
        info = self.create_info(view_id, "image view")
        if info is None or info.FindChild("image") is None:
            return None, 0
        img = int(info.FindChild("image").AsResourceId())
        mip = 0
        rng = info.FindChild("subresourceRange")
        if rng is not None and rng.FindChild("baseMipLevel") is not None:
            mip = rng.FindChild("baseMipLevel").AsInt()
        return img, mip

    def image_format(self, rid):
        """VK_FORMAT_... of an image: its vkCreateImage record, or for a swapchain image (which has
        none) its swapchain's imageFormat; None when neither is recorded."""
        info = self.create_info(rid, "image")
        if info is not None and info.FindChild("format") is not None:
            return info.FindChild("format").AsString()
        r = self.resources.get(int(rid))
        for parent in (r.parentResources if r is not None else []):
            pinfo = self.create_info(parent, "swapchain")
            if pinfo is not None and pinfo.FindChild("imageFormat") is not None:
                return pinfo.FindChild("imageFormat").AsString()
        return None

    def name(self, rid):
        """The resource's name as RenderDoc shows it (e.g. 'Image 135')."""
        r = self.resources.get(int(rid))
        return r.name if r is not None else "resource %d" % int(rid)
