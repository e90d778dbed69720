"""Images of the capture as PNG files, and texel sizes of formats, for rdc_export.py.

RenderDoc 1.24's SaveTexture crashes on a swapchain image under lavapipe, so every image is read
with GetTextureData (the base mip level, first layer) and encoded here (PNG spec 11.2, 12.7).
Saved: 8-bit RGB(A)/BGR(A) as RGB; 8-bit R and RG as grey (R only); depth formats D16, D24(S8),
D32(S8) as grey normalised to the image's own depth range (the range is returned so the caller
can record it). Anything else (block-compressed, packed, float colour) is not saved and the reason
is returned.
"""

import struct
import zlib


def write_png(path, width, height, filtered_rows, grey=False):
    """An 8-bit RGB (or grey) PNG from rows that already carry their filter byte."""

    def chunk(tag, body):
        return struct.pack(">I", len(body)) + tag + body + struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF)

    colour_type = 0 if grey else 2
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(filtered_rows, 6)) + chunk(b"IEND", b""))


def texel_bytes(rd, fmt):
    """Bytes of one texel (or of one 4x4 block for block-compressed formats, with block=True) of a
    RenderDoc ResourceFormat: (bytes, block_edge)."""
    t = fmt.type
    if t == rd.ResourceFormatType.Regular:
        return fmt.compByteWidth * fmt.compCount, 1
    special = {rd.ResourceFormatType.D16S8: 4, rd.ResourceFormatType.D24S8: 4, rd.ResourceFormatType.D32S8: 8,
               rd.ResourceFormatType.S8: 1, rd.ResourceFormatType.A8: 1, rd.ResourceFormatType.R4G4: 1,
               rd.ResourceFormatType.R10G10B10A2: 4, rd.ResourceFormatType.R11G11B10: 4,
               rd.ResourceFormatType.R9G9B9E5: 4, rd.ResourceFormatType.R5G6B5: 2,
               rd.ResourceFormatType.R5G5B5A1: 2, rd.ResourceFormatType.R4G4B4A4: 2}
    if t in special:
        return special[t], 1
    blocks = {rd.ResourceFormatType.BC1: 8, rd.ResourceFormatType.BC4: 8, rd.ResourceFormatType.BC2: 16,
              rd.ResourceFormatType.BC3: 16, rd.ResourceFormatType.BC5: 16, rd.ResourceFormatType.BC6: 16,
              rd.ResourceFormatType.BC7: 16, rd.ResourceFormatType.ETC2: 8, rd.ResourceFormatType.EAC: 8,
              rd.ResourceFormatType.ASTC: 16}
    if t in blocks:
        return blocks[t], 4
    return max(1, fmt.ElementSize()), 1


def is_depth(rd, fmt):
    """True for a depth (or depth-stencil) format."""
    return (fmt.type in (rd.ResourceFormatType.D16S8, rd.ResourceFormatType.D24S8, rd.ResourceFormatType.D32S8)
            or (fmt.type == rd.ResourceFormatType.Regular and fmt.compType == rd.CompType.Depth))


def depth_values(rd, fmt, data, count):
    """The depth of `count` texels of GetTextureData bytes as floats 0..1 (stencil dropped), or None.
    RenderDoc returns D24 formats (X8_D24, D24S8) as 32-bit words with depth in the low 24 bits,
    D32S8 as 8 bytes a texel with the float first, D16 as 16-bit words."""
    if count == 0 or len(data) < count * 2:
        return None
    stride = len(data) // count
    t = fmt.type
    if t == rd.ResourceFormatType.D24S8 or (t == rd.ResourceFormatType.Regular and fmt.compByteWidth == 3):
        if stride != 4:
            return None
        return [(w & 0xFFFFFF) / 16777215.0 for w in struct.unpack_from("<%dI" % count, data)]
    if t == rd.ResourceFormatType.D32S8 or (t == rd.ResourceFormatType.Regular and fmt.compByteWidth == 4):
        return [struct.unpack_from("<f", data, i * stride)[0] for i in range(count)]
    if t == rd.ResourceFormatType.D16S8 or (t == rd.ResourceFormatType.Regular and fmt.compByteWidth == 2):
        return [struct.unpack_from("<H", data, i * stride)[0] / 65535.0 for i in range(count)]
    return None


def save_texture(rd, c, tex, path, event):
    """Writes texture `tex` (a TextureDescription) read at `event` (None: the replay's current event)
    as a PNG.
    Returns (True, note or None) when saved, (False, reason) when not."""
    if tex.msSamp > 1:
        return False, "multisampled (%d samples): not read back (RenderDoc 1.24 crashes on some on lavapipe)" % tex.msSamp
    if event is not None:
        c.SetFrameEvent(event, True)
    f = tex.format
    w, h = tex.width, tex.height
    data = c.GetTextureData(tex.resourceId, rd.Subresource())
    if f.type == rd.ResourceFormatType.Regular and f.compByteWidth == 1 and f.compType != rd.CompType.Depth:
        n = f.compCount
        if len(data) < w * h * n:
            return False, "%d bytes returned, %dx%dx%d expected" % (len(data), w, h, n)
        if n in (3, 4):
            write_png(path, w, h, _rgb_rows(data, w, h, n, f.BGRAOrder()))
            return True, None
        write_png(path, w, h, _grey_rows(data, w, h, n), grey=True)
        return True, "saved as grey (channel R of %d)" % n
    if is_depth(rd, f):
        vals = depth_values(rd, f, data, w * h)
        if vals is None:
            return False, "depth format %s not decoded" % f.Name()
        lo, hi = min(vals), max(vals)
        scale = 255.0 / (hi - lo) if hi > lo else 0.0
        grey = bytes(int(round((v - lo) * scale)) for v in vals)
        write_png(path, w, h, _grey_rows(grey, w, h, 1), grey=True)
        return True, "depth saved as grey, normalised from [%.6g, %.6g] to [0, 255]" % (lo, hi)
    return False, "format %s is not saved as an image (8-bit colour and depth only)" % f.Name()


def _rgb_rows(data, w, h, n, bgra):
    """PNG rows (filter byte 0) of RGB from n-component 8-bit texels."""
    rows = []
    r, b = (2, 0) if bgra else (0, 2)
    for y in range(h):
        row = data[y * w * n:(y + 1) * w * n]
        rgb = bytearray(w * 3)
        rgb[0::3] = row[r::n]
        rgb[1::3] = row[1::n]
        rgb[2::3] = row[b::n]
        rows.append(b"\0" + bytes(rgb))
    return b"".join(rows)


def _grey_rows(data, w, h, n):
    """PNG rows (filter byte 0) of grey from the first component of n-component 8-bit texels."""
    return b"".join(b"\0" + bytes(data[y * w * n:(y + 1) * w * n][0::n]) for y in range(h))
