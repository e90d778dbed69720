#!/usr/bin/python3
"""Captures one frame of a running Vulkan or OpenGL application with RenderDoc (no display needed beyond Xvfb).

usage: xvfb-run -a -s "-screen 0 1280x720x24" /usr/bin/python3 capture_frame.py OUT [--after S | --frame N]
           [--count N] [--gl] [--final-png FILE.png] [--timeout S] -- APP [ARGS...]

Launches APP with RenderDoc's capture layer, waits --after seconds (default 1) for it to render, or
until its frame N (--frame, counted in presents), asks for one frame (or --count consecutive ones:
a sequence, each frame its own capture, OUT_0.rdc, OUT_1.rdc, ...) and prints the captures' paths.
OUT is a file template (the capture is OUT_frameN.rdc) or, ending in .rdc, the capture's exact path.
`renderdoccmd capture` alone cannot choose a frame without a keyboard (it captures on F12/PrtScn),
hence this script. Exit 2 with one line on failure.

A Vulkan application is launched with renderdoc.ExecuteAndInject (LD_PRELOAD of librenderdoc.so).
--gl runs an OpenGL (or OpenGL ES through GLX/EGL) application as Vulkan: Mesa's zink driver on
lavapipe (Mesa 22.3: LIBGL_ALWAYS_SOFTWARE=1 makes zink accept a CPU Vulkan device and the GLX
loader take the software (kopper) path that works under Xvfb without DRI3;
MESA_LOADER_DRIVER_OVERRIDE=zink picks zink instead of llvmpipe; VK_ICD_FILENAMES pins lavapipe).
RenderDoc is then loaded only as the implicit Vulkan layer (ENABLE_VULKAN_RENDERDOC_CAPTURE=1,
capture file and options through RENDERDOC_CAPFILE/RENDERDOC_CAPOPTS), not preloaded: preloaded, it
also hooks OpenGL and draws its GL overlay text through zink into the frame, where the Vulkan
capture records it as the application's own draws. The Vulkan layer's overlay is drawn only
between captured frames and never appears in a capture. APP is terminated after the capture.
--final-png writes the presented image of the captured frame (replayed, GetTextureData) as a PNG.
Examples (docs/capture-import.md):
  xvfb-run -a -s "-screen 0 1280x720x24" /usr/bin/python3 scripts/capture/capture_frame.py /tmp/vkcube -- \
      /usr/bin/vkcube --c 3000 --width 320 --height 240
  xvfb-run -a -s "-screen 0 1280x720x24" /usr/bin/python3 scripts/capture/capture_frame.py \
      /tmp/shading.rdc --gl --after 5 -- /usr/bin/glmark2 --size 320x240 -b shading:shading=phong:duration=60
"""

import os
import shutil
import struct
import subprocess
import sys
import time
import zlib

PROG = "capture_frame.py"
LAVAPIPE_ICD = "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json"


class Failure(Exception):
    pass


def zink_environment():
    """The environment that runs GL through zink on lavapipe (Mesa 22.3) and loads RenderDoc's Vulkan layer."""
    if not os.path.isfile(LAVAPIPE_ICD):
        raise Failure("lavapipe's Vulkan ICD %s is missing (mesa-vulkan-drivers; scripts/install_capture_deps.sh)"
                      % LAVAPIPE_ICD)
    if not os.path.isfile("/usr/lib/x86_64-linux-gnu/dri/zink_dri.so"):
        raise Failure("Mesa's zink driver is missing (libgl1-mesa-dri; scripts/install_capture_deps.sh)")
    env = dict(os.environ)
    env.update({
        "LIBGL_ALWAYS_SOFTWARE": "1",
        "MESA_LOADER_DRIVER_OVERRIDE": "zink",
        "VK_ICD_FILENAMES": LAVAPIPE_ICD,
        "ENABLE_VULKAN_RENDERDOC_CAPTURE": "1",
    })
    for name in ("LD_PRELOAD", "GALLIUM_DRIVER", "VK_DRIVER_FILES", "VK_INSTANCE_LAYERS", "VK_LOADER_LAYERS_ENABLE",
                 "VK_LOADER_LAYERS_DISABLE", "DISABLE_VULKAN_RENDERDOC_CAPTURE_1_24"):
        env.pop(name, None)
    if not os.path.isdir(env.get("XDG_RUNTIME_DIR", "")):
        # lavapipe's WSI prints an error per instance without one; harmless, but keep the log clean
        xdg = "/tmp/capture_frame-runtime-%d" % os.getuid()
        os.makedirs(xdg, mode=0o700, exist_ok=True)
        env["XDG_RUNTIME_DIR"] = xdg
    return env


def check_zink(env):
    """glxinfo -B with the same environment (without the layer) must name zink on llvmpipe (lavapipe)."""
    glxinfo = shutil.which("glxinfo")
    if not glxinfo:
        return  # mesa-utils not installed: nothing to check with
    env = dict(env)
    del env["ENABLE_VULKAN_RENDERDOC_CAPTURE"]
    try:
        out = subprocess.run([glxinfo, "-B"], env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, timeout=60).stdout.decode("utf-8", "replace")
    except subprocess.TimeoutExpired:
        raise Failure("glxinfo -B hung with the zink environment")
    renderer = [l.split(":", 1)[1].strip() for l in out.splitlines() if l.startswith("OpenGL renderer string")]
    if not renderer or not renderer[0].startswith("zink") or "llvmpipe" not in renderer[0]:
        last = [l for l in out.splitlines() if l.strip()]
        raise Failure("OpenGL does not run on zink/lavapipe here (glxinfo -B: %s)"
                      % (renderer[0] if renderer else (last[-1] if last else "no output")))


def launch_gl(rd, app, template):
    """Starts APP through zink with RenderDoc loaded only as its Vulkan layer; returns the process."""
    env = zink_environment()
    check_zink(env)
    env["RENDERDOC_CAPFILE"] = template
    env["RENDERDOC_CAPOPTS"] = rd.GetDefaultCaptureOptions().EncodeAsString()
    # its output goes to stderr: stdout carries only the capture's path
    return subprocess.Popen(app, env=env, stdin=subprocess.DEVNULL, stdout=sys.stderr)


def connect_gl(rd, app, proc, wait=60):
    """The target control of PROC. librenderdoc.so is loaded when zink creates its Vulkan instance and
    its server listens on the first free port from 38920. A GL application may create and destroy a
    first zink screen (instance) before the one it renders with: the layer is then unloaded and
    loaded again, so the connection can drop once and is made again here."""
    deadline = time.time() + wait
    while time.time() < deadline:
        if proc.poll() is not None:
            raise Failure("%s exited (status %d) before a frame was captured" % (app[0], proc.returncode))
        ident = rd.EnumerateRemoteTargets("", 0)
        while ident:
            tc = rd.CreateTargetControl("", ident, "tbdrsim", True)
            if tc:
                if tc.GetPID() == proc.pid:
                    return tc
                tc.Shutdown()
            ident = rd.EnumerateRemoteTargets("", ident)
        time.sleep(0.2)
    raise Failure("RenderDoc's Vulkan layer is not loaded in %s after %d s (is its GL driver zink? "
                  "glxinfo -B with the same environment)" % (app[0], wait))


def launch_vulkan(rd, app, template):
    res = rd.ExecuteAndInject(app[0], os.getcwd(), " ".join(app[1:]), [], template, rd.GetDefaultCaptureOptions(),
                              False)
    if res.result != rd.ResultCode.Succeeded:
        raise Failure("RenderDoc could not launch %s (%s)" % (app[0], res.result))
    return res.ident


def connect_vulkan(rd, app, ident):
    for _ in range(100):
        tc = rd.CreateTargetControl("", ident, "tbdrsim", True)
        if tc:
            return tc
        time.sleep(0.1)
    raise Failure("cannot connect to RenderDoc in %s (it ended?)" % app[0])


def capture(rd, args, app, connect, proc):
    """Asks for --count consecutive frames (after --after seconds or from --frame) and returns the
    captures' paths, one file a frame, in order."""
    paths = []
    launched = time.time()
    tc = connect()
    asked = first_ask = None
    try:
        while True:
            now = time.time()
            if asked is None and (args["frame"] is not None or now - launched >= args["after"]):
                if args["frame"] is not None:
                    tc.QueueCapture(args["frame"], args["count"])
                else:
                    tc.TriggerCapture(args["count"])
                asked = now
                first_ask = first_ask or now
            if first_ask is not None and now - first_ask > args["timeout"]:
                raise Failure("no capture from %s %g s after asking for it (no frame presented?)"
                              % (app[0], args["timeout"]))
            msg = tc.ReceiveMessage(None)
            if msg.type == rd.TargetControlMessageType.NewCapture:
                paths.append(msg.newCapture.path)
                if len(paths) == args["count"]:
                    return paths
                continue
            if msg.type == rd.TargetControlMessageType.Disconnected:
                tc.Shutdown()
                tc = None
                if proc is None:
                    raise Failure("%s ended or hung before a frame was captured (try a longer run or a smaller "
                                  "--after)" % app[0])
                print("%s: the connection to RenderDoc in %s dropped, reconnecting" % (PROG, app[0]), file=sys.stderr)
                tc = connect()  # the layer was reloaded (see connect_gl), or the process ended: raises
                asked = None
                paths = []
                continue
            time.sleep(0.05)
    finally:
        if tc is not None:
            tc.Shutdown()


def write_png(path, width, height, rgb_rows):
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xffffffff)
    raw = b"".join(b"\x00" + row for row in rgb_rows)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def final_png(rd, capture, out):
    """Replays CAPTURE and writes the image its last present shows (8-bit RGBA/BGRA targets) as a PNG."""
    rd.InitialiseReplay(rd.GlobalEnvironment(), [])
    cap = rd.OpenCaptureFile()
    try:
        if cap.OpenFile(capture, "", None) != rd.ResultCode.Succeeded:
            raise Failure("RenderDoc cannot open %s" % capture)
        result, ctrl = cap.OpenCapture(rd.ReplayOptions(), None)
        if result != rd.ResultCode.Succeeded:
            raise Failure("RenderDoc cannot replay %s (%s)" % (capture, result))
        try:
            actions, stack = [], list(reversed(ctrl.GetRootActions()))
            while stack:
                a = stack.pop()
                actions.append(a)
                stack.extend(reversed(a.children))
            presents = [a for a in actions if a.flags & rd.ActionFlags.Present]
            draws = [a for a in actions if a.flags & rd.ActionFlags.Drawcall]
            if presents and presents[-1].copyDestination != rd.ResourceId.Null():
                event, target = presents[-1].eventId, presents[-1].copyDestination
            elif draws:
                event, target = draws[-1].eventId, draws[-1].outputs[0]
            else:
                raise Failure("%s has no present and no draw" % capture)
            ctrl.SetFrameEvent(event, True)
            tex = [t for t in ctrl.GetTextures() if t.resourceId == target][0]
            fmt = tex.format
            if fmt.compByteWidth != 1 or fmt.compCount not in (3, 4):
                raise Failure("%s: final target format %s is not 8-bit RGB(A)" % (capture, fmt.Name()))
            data = ctrl.GetTextureData(target, rd.Subresource(0, 0, 0))
            bpp, order = fmt.compCount, ((2, 1, 0) if fmt.BGRAOrder() else (0, 1, 2))
            rows = []
            for y in range(tex.height):
                line = data[y * tex.width * bpp:(y + 1) * tex.width * bpp]
                row = bytearray(tex.width * 3)
                for c, src in enumerate(order):
                    row[c::3] = line[src::bpp]
                rows.append(bytes(row))
            write_png(out, tex.width, tex.height, rows)
        finally:
            ctrl.Shutdown()
    finally:
        cap.Shutdown()
        rd.ShutdownReplay()


def parse(argv):
    if "--" not in argv or argv.index("--") < 1 or argv.index("--") == len(argv) - 1:
        raise Failure("usage: %s OUT [--after S | --frame N] [--gl] [--final-png FILE] [--timeout S] -- APP [ARGS...]"
                      % PROG)
    split = argv.index("--")
    opts, app = argv[:split], argv[split + 1:]
    args = {"out": opts[0], "after": 1.0, "frame": None, "gl": False, "png": None, "timeout": 120.0, "count": 1}
    i = 1
    while i < len(opts):
        o = opts[i]
        if o == "--gl":
            args["gl"] = True
            i += 1
            continue
        if o not in ("--after", "--frame", "--final-png", "--timeout", "--count") or i + 1 >= len(opts):
            raise Failure("unknown option or missing value: %s" % o)
        v = opts[i + 1]
        try:
            if o == "--after":
                args["after"] = float(v)
            elif o == "--frame":
                args["frame"] = int(v)
            elif o == "--timeout":
                args["timeout"] = float(v)
            elif o == "--count":
                args["count"] = int(v)
                if not 1 <= args["count"] <= 1000:
                    raise ValueError(v)
            else:
                args["png"] = v
        except ValueError:
            raise Failure("%s needs a number, not %s" % (o, v))
        i += 2
    return args, app


def main(argv):
    try:
        args, app = parse(argv)
        try:
            import renderdoc as rd
        except ImportError:
            raise Failure("python3-renderdoc is not installed (scripts/install_capture_deps.sh)")
        exe = app[0] if os.path.isabs(app[0]) else (shutil.which(app[0]) or app[0])
        if not os.path.isfile(exe):
            raise Failure("application %s not found" % app[0])
        app = [exe] + app[1:]
        out = os.path.abspath(args["out"])
        exact = out.endswith(".rdc")
        template = out[:-4] + ".capture_frame_tmp" if exact else out
        if not os.path.isdir(os.path.dirname(out)):
            raise Failure("folder %s does not exist" % os.path.dirname(out))
        if "DISPLAY" not in os.environ:
            raise Failure("no DISPLAY: run under xvfb-run (the application presents to an X11 window)")
        if args["gl"]:
            proc = launch_gl(rd, app, template)
            connect = lambda: connect_gl(rd, app, proc)
        else:
            proc, ident = None, launch_vulkan(rd, app, template)
            connect = lambda: connect_vulkan(rd, app, ident)
        try:
            paths = capture(rd, args, app, connect, proc)
        finally:
            if proc is not None:
                proc.terminate()
                try:
                    proc.wait(10)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
        written = []
        for k, path in enumerate(paths):
            # the layer writes the file as it sends NewCapture: wait until its size is stable
            last = -1
            for _ in range(100):
                size = os.path.getsize(path) if os.path.isfile(path) else -1
                if size > 0 and size == last:
                    break
                last = size
                time.sleep(0.1)
            if exact:  # OUT.rdc, or OUT_0.rdc, OUT_1.rdc, ... for --count N
                target = out if len(paths) == 1 else "%s_%d.rdc" % (out[:-4], k)
                os.replace(path, target)
                path = target
            written.append(path)
        if args["png"]:
            final_png(rd, written[-1], args["png"])
        for path in written:
            print(path)
        return 0
    except Failure as e:
        print("%s: %s" % (PROG, e), file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
