#!/usr/bin/python3
"""Exports one frame of a RenderDoc capture (.rdc) to tbdrsim's capture intermediate (frame.json).

usage: rdc_export.py CAPTURE.rdc OUTDIR [--history-samples N] [--history-method readback|pixelhistory]

Runs RenderDoc's replay (python3-renderdoc, Debian's /usr/bin/python3) and writes into OUTDIR:
  frame.json     format `tbdrsim-capture 2`: passes (render passes and dynamic rendering) with their
                 sizes, attachments (load/store/clear, resolves), per draw: pipeline state (depth clip
                 convention, clamp, bias), post-vertex-shader clip positions of every instance, the
                 vertex and fragment shaders' static SPIR-V cost, bound textures; transfers with
                 their bytes; dispatches with their cost; the frame's commands in submission order;
                 what was not supported, one line each naming the event
  reference.png  the application's own final colour image (the last draw's first colour target)
  tex_<id>.png   the sampled textures a draw binds (8-bit colour as RGB, R8 and depth as grey)
  draw_ids.bin   per pixel of the final image, the event of the last draw that changed it (uint32
                 little-endian, 0 = none; readback method only)
The format of frame.json is docs/capture-import.md ("The intermediate") with the changes of
`tbdrsim-capture 2`; `tbdrsim import` turns it into a trace and a GLB. Errors: one line naming the
event at fault, exit 2, nothing written. Only Vulkan captures are read (OpenGL applications are
captured through Mesa's zink, which records Vulkan).
The work is split over export_sd.py (structured data), export_passes.py, export_draws.py,
export_transfers.py, export_images.py and export_history.py.
"""

import json
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from export_sd import ExportError, Records, fail  # noqa: E402,F401  (ExportError is this module's error)

PROG = os.environ.get("TBDRSIM_PLOT_PROG", "rdc_export.py")


def export(rdc_path, outdir, history_samples, history_method="readback"):
    """Opens the capture with RenderDoc and exports it into outdir; raises ExportError."""
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
        return export_replay(rd, c, rdc_path, outdir, history_samples, api, history_method)
    finally:
        if c is not None:
            c.Shutdown()
        if cap is not None:
            cap.Shutdown()
        rd.ShutdownReplay()


# Dynamic state calls that change what clip coordinates or depth mean; RenderDoc 1.24 records none
# of them (no extended dynamic state 3), so a capture holding one is refused rather than misread.
CLIP_STATE_CALLS = ("vkCmdSetDepthClipNegativeOneToOneEXT", "vkCmdSetDepthClampEnableEXT",
                    "vkCmdSetDepthClipEnableEXT", "vkCmdSetViewportSwizzleNV", "vkCmdSetPolygonModeEXT")
TRANSFER_FLAGS = ("Clear", "Copy", "Resolve", "GenMips")


def all_actions(c):
    """Every action of the frame, depth first (submission order)."""
    out = []

    def walk(a):
        out.append(a)
        for ch in a.children:
            walk(ch)

    for a in c.GetRootActions():
        walk(a)
    return out


def refuse_clip_state_calls(sf):
    """Fails on a recorded dynamic state call that changes clip or depth meaning (CLIP_STATE_CALLS)."""
    for i, ch in enumerate(sf.chunks):
        if ch.name in CLIP_STATE_CALLS:
            fail("chunk %d: %s recorded; this dynamic state changes what clip coordinates or depth mean and "
                 "is not read" % (i, ch.name))


class FrameExport:
    """Walks the frame's actions once and builds frame.json's passes, transfers, dispatches, commands."""

    def __init__(self, rd, c, outdir):
        from export_draws import DrawReader
        from export_passes import PassReader
        from export_transfers import TransferReader
        self.rd = rd
        self.c = c
        self.sf = c.GetStructuredFile()
        self.textures = {int(t.resourceId): t for t in c.GetTextures()}
        buffers = {int(b.resourceId): b for b in c.GetBuffers()}
        records = Records(self.sf, {int(r.resourceId): r for r in c.GetResources()})
        self.unsupported = []
        self.passes = PassReader(rd, self.sf, records, self.textures, self.unsupported)
        self.draws = DrawReader(rd, c, self.textures, outdir, self.unsupported)
        self.transfers = TransferReader(rd, c, self.sf, records, self.textures, buffers, self.unsupported)
        self.actions = all_actions(c)

    def is_any(self, a, names):
        """Does action `a` carry any of the named ActionFlags."""
        return any(a.flags & getattr(self.rd.ActionFlags, n) for n in names)

    def walk(self, frame):
        """Fills frame's passes, transfers, dispatches and commands; returns the draws in order."""
        current, draws = None, []
        for a in self.actions:
            name = a.GetName(self.sf)
            if self.is_any(a, ("CommandBufferBoundary",)):
                continue  # vkBeginCommandBuffer / vkEndCommandBuffer markers, not render passes
            if self.is_any(a, ("BeginPass",)):
                if current is not None:
                    fail("event %d: %s inside an open render pass" % (a.eventId, name))
                current = self.passes.describe(a)
                continue
            if self.is_any(a, ("EndPass",)):
                if current is None:
                    fail("event %d: %s without a render pass" % (a.eventId, name))
                frame["passes"].append(current)
                frame["commands"].append({"kind": "pass", "event": current["event"]})
                current = None
                continue
            if self.is_any(a, ("Dispatch",)):
                frame["dispatches"].append(self.transfers.dispatch(a, name))
                frame["commands"].append({"kind": "dispatch", "event": a.eventId})
                continue
            if self.is_any(a, TRANSFER_FLAGS):
                self.transfer(a, name, current, frame)
                continue
            if not self.is_any(a, ("Drawcall",)):
                continue
            if current is None:
                fail("draw at event %d (%s): outside a render pass" % (a.eventId, name))
            draw = self.draws.export(a, name)
            fetch = attachment_reads(current, draw)
            if fetch:
                draw["fetch"] = fetch
            current["draws"].append(draw)
            draws.append(draw)
        if current is not None:
            fail("render pass begun at event %d is not ended in the capture (truncated frame?)" % current["event"])
        return draws

    def transfer(self, a, name, current, frame):
        """A Copy/Resolve/Clear/GenMips action: a transfer outside a pass; inside a pass (vkCmdClearAttachments)
        it is recorded on the pass and listed as unsupported."""
        if current is not None:
            current.setdefault("clear_attachments", []).append({"event": a.eventId, "name": name})
            self.unsupported.append("event %d: %s - clear inside a render pass, not simulated" % (a.eventId, name))
            return
        t = self.transfers.export(a, name)
        if t is not None:
            frame["transfers"].append(t)
            frame["commands"].append({"kind": "transfer", "event": a.eventId})


def attachment_reads(p, draw):
    """Indices of the pass's attachments the draw's fragment shader reads (input attachments, local
    read, or a bound texture that is an attachment of its own pass)."""
    read = {t["id"] for t in draw.get("textures", [])}
    return [att["index"] for att in p["attachments"] if att.get("image") in read]


def export_replay(rd, c, rdc_path, outdir, history_samples, api, history_method="readback"):
    """frame.json's content for an open replay (see the module docstring)."""
    from export_images import save_texture
    fx = FrameExport(rd, c, outdir)
    refuse_clip_state_calls(fx.sf)
    frame = {"format": "tbdrsim-capture 2", "source": {"tool": "renderdoc", "renderdoc_version": rd.GetVersionString(),
                                                     "api": api, "capture": os.path.basename(rdc_path)},
             "clip_convention": "vulkan", "passes": [], "dispatches": [], "transfers": [], "commands": [],
             "unsupported": fx.unsupported}
    draws = fx.walk(frame)
    final = [d for d in draws if d["targets"]]
    if not final:
        fail("%s: no draw writes a colour target; nothing to import" % rdc_path)
    final_target = final[-1]["targets"][0]
    tex = fx.textures[final_target]
    frame["width"], frame["height"] = tex.width, tex.height
    frame["final_target"] = final_target
    # The application's own frame: the final colour target after the frame's last event (its pass's
    # store has happened by then).
    last_event = max(a.eventId for a in fx.actions)
    shown = presented_image(frame, final_target, final[-1]["event"])
    if shown != final_target:
        frame["reference_target"] = shown
    ok, note = save_texture(rd, c, fx.textures[shown], os.path.join(outdir, "reference.png"), last_event)
    if ok:
        frame["reference_image"] = "reference.png"
    else:
        fx.unsupported.append("final target %d: reference image not saved: %s" % (final_target, note))
    if history_samples > 0:
        frame["pixel_history"] = pixel_history(rd, c, fx, frame, draws, final_target, history_samples,
                                               history_method, outdir)
    return frame


def presented_image(frame, target, last_draw):
    """The image holding the application's frame: the final target, or when it is multisampled the
    image it is resolved into after the last draw (a resolve attachment of its pass, or a later
    vkCmdResolveImage)."""
    for p in frame["passes"]:
        atts = {a["index"]: a for a in p["attachments"]}
        for a in p["attachments"]:
            src = atts.get(a.get("resolve_of"))
            if src is not None and src.get("image") == target and a.get("image") is not None:
                target = a["image"]
    for t in frame["transfers"]:
        if t["kind"] == "resolve" and t["src_image"] == target and t["event"] > last_draw:
            return t["dst_image"]
    return target


def pixel_history(rd, c, fx, frame, draws, target, history_samples, method, outdir):
    """`pixel_history`: which draw and triangle wrote each sampled pixel of the final image
    (export_history.py); the method and its time are recorded."""
    import export_history
    tex = fx.textures[target]
    step, grid = export_history.sample_grid(tex.width, tex.height, history_samples)
    start = time.time()
    log = {"method": method}
    if method == "readback" and tex.msSamp > 1:
        # RenderDoc 1.24 on lavapipe crashes at the next replay after reading a multisampled image.
        method = log["method"] = "pixelhistory"
        log["note"] = "the final target is multisampled (%d samples), which is not read back" % tex.msSamp
    if method == "pixelhistory":
        samples = export_history.by_pixelhistory(rd, c, tex.resourceId, grid, {d["event"] for d in draws},
                                                 max(a.eventId for a in fx.actions))
    else:
        samples = export_history.by_readback(rd, c, fx.actions, draws, target, step, grid, fx.textures, outdir,
                                               log)
        frame["draw_id_image"] = "draw_ids.bin"
    log["seconds"] = round(time.time() - start, 2)
    out = {"step": step, "samples": samples}
    out.update(log)
    return out


def main(argv):
    import argparse
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n")[0])
    ap.add_argument("capture")
    ap.add_argument("outdir")
    ap.add_argument("--history-samples", type=int, default=1200,
                    help="pixels of the final image whose draw and triangle are recorded (0: none)")
    ap.add_argument("--history-method", choices=("readback", "pixelhistory"), default="readback",
                    help="readback: one image readback per draw, triangles found from the clip positions "
                         "(PixelHistory only where that cannot decide); pixelhistory: RenderDoc's "
                         "PixelHistory at every sampled pixel (format 1's method, slow on large frames)")
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
            frame = export(args.capture, tmp, args.history_samples, args.history_method)
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
