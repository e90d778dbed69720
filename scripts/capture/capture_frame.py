#!/usr/bin/python3
"""Captures one frame of a running Vulkan application with RenderDoc (no display needed beyond Xvfb).

usage: xvfb-run -a -s "-screen 0 1280x720x24" /usr/bin/python3 capture_frame.py OUT_TEMPLATE [--after S] -- APP [ARGS...]

Launches APP with RenderDoc's capture layer injected (renderdoc.ExecuteAndInject), waits --after
seconds (default 1) for it to render, asks for one frame (TriggerCapture) and prints the capture's
path (OUT_TEMPLATE_frameN.rdc). `renderdoccmd capture` alone cannot choose a frame without a
keyboard (it captures on F12/PrtScn), hence this script. Exit 2 with one line on failure.
Example (docs/capture-import.md):
  xvfb-run -a -s "-screen 0 1280x720x24" /usr/bin/python3 scripts/capture/capture_frame.py /tmp/vkcube -- \
      /usr/bin/vkcube --c 3000 --width 320 --height 240
"""

import os
import sys
import time

PROG = "capture_frame.py"


def main(argv):
    if "--" not in argv or argv.index("--") < 1 or argv.index("--") == len(argv) - 1:
        print(__doc__, file=sys.stderr)
        return 2
    split = argv.index("--")
    opts, app = argv[:split], argv[split + 1:]
    template = opts[0]
    after = 1.0
    if "--after" in opts:
        after = float(opts[opts.index("--after") + 1])
    try:
        import renderdoc as rd
    except ImportError:
        print("%s: python3-renderdoc is not installed (scripts/install_capture_deps.sh)" % PROG, file=sys.stderr)
        return 2
    if not os.path.isfile(app[0]):
        print("%s: application %s not found" % (PROG, app[0]), file=sys.stderr)
        return 2
    res = rd.ExecuteAndInject(app[0], os.getcwd(), " ".join(app[1:]), [], template, rd.GetDefaultCaptureOptions(),
                              False)
    if res.result != rd.ResultCode.Succeeded:
        print("%s: RenderDoc could not launch %s (%s)" % (PROG, app[0], res.result), file=sys.stderr)
        return 2
    tc = None
    for _ in range(100):
        tc = rd.CreateTargetControl("", res.ident, "tbdrsim", True)
        if tc:
            break
        time.sleep(0.1)
    if not tc:
        print("%s: cannot connect to RenderDoc in %s" % (PROG, app[0]), file=sys.stderr)
        return 2
    time.sleep(after)
    tc.TriggerCapture(1)
    start = time.time()
    path = None
    while time.time() - start < 120:
        msg = tc.ReceiveMessage(None)
        if msg.type == rd.TargetControlMessageType.NewCapture:
            path = msg.newCapture.path
            break
        if msg.type == rd.TargetControlMessageType.Disconnected:
            break
    tc.Shutdown()
    if not path:
        print("%s: %s ended or hung before a frame was captured (try a longer run or a smaller --after)"
              % (PROG, app[0]), file=sys.stderr)
        return 2
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
