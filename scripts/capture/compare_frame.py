#!/usr/bin/python3
"""Compares a replayed imported frame with the application's own frame.

usage: compare_frame.py CAPTURE_DIR IMAGES_DIR [--out SIDE_BY_SIDE.png]

CAPTURE_DIR holds the capture intermediate (frame.json with its pixel history samples, and
reference.png, the application's frame); IMAGES_DIR is what `tbdrsim run --images` wrote
(color.png, triangle_id.png). Prints:
- coverage, whole frame: pixels where both frames are background or both covered; the reference's
  coverage is draw_ids.bin when the export wrote it (format 2: the pixels some draw changed), else
  the pixels differing from the final colour attachment's clear colour (format 1);
- triangle, at the sampled pixels: a pixel matches when its captured triangle (RenderDoc pixel
  history: event and primitive id) and its simulated triangle (triangle_id.png colour) are each
  the other's most frequent partner - a one-to-one matching, so one triangle everywhere cannot score;
- colour: mean absolute difference (0..255) over the pixels covered in both.
Writes reference | simulated colour | simulated triangle ids side by side with --out.
Exit 2 with one line on bad input.
"""

import argparse
import collections
import json
import os
import sys

import numpy as np
from PIL import Image

PROG = "compare_frame.py"


def load_rgb(path):
    if not os.path.isfile(path):
        raise SystemExit("%s: %s not found" % (PROG, path))
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.int32)


def reference_coverage(frame, capture_dir, ref):
    """(covered pixels of the application's frame, how) or (None, why not). From draw_ids.bin when the
    export wrote it (format 2: per pixel the event of the last draw that changed it, 0 = none), else
    the pixels that differ from the final target's clear colour (format 1)."""
    shape = ref.shape
    name = frame.get("draw_id_image")
    if name:
        path = os.path.join(capture_dir, name)
        if not os.path.isfile(path):
            return None, "%s not found" % path
        ids = np.fromfile(path, dtype="<u4")
        if ids.size != shape[0] * shape[1]:
            return None, "%s holds %d pixels, the frame has %dx%d" % (path, ids.size, shape[1], shape[0])
        return ids.reshape(shape[0], shape[1]) != 0, "pixels a draw changed (%s)" % name
    for p in frame["passes"]:
        for att in p["attachments"]:
            if att.get("image") == frame.get("final_target") and att["load"] == "clear":
                clear = np.array([round(255 * min(max(c, 0.0), 1.0)) for c in att["clear"]["color"][:3]])
                return np.any(np.abs(ref - clear) > 1, axis=2), "pixels differing from the clear colour"
    return None, "the final target is not cleared in the capture; coverage of the reference is unknown"


def main(argv):
    ap = argparse.ArgumentParser(prog=PROG)
    ap.add_argument("capture_dir")
    ap.add_argument("images_dir")
    ap.add_argument("--out")
    a = ap.parse_args(argv)
    try:
        with open(os.path.join(a.capture_dir, "frame.json")) as f:
            frame = json.load(f)
        ref = load_rgb(os.path.join(a.capture_dir, frame.get("reference_image", "reference.png")))
        sim = load_rgb(os.path.join(a.images_dir, "color.png"))
        ids = load_rgb(os.path.join(a.images_dir, "triangle_id.png"))
    except (OSError, ValueError) as e:
        print("%s: %s" % (PROG, e), file=sys.stderr)
        return 2
    except SystemExit as e:
        print(e, file=sys.stderr)
        return 2
    # A frame whose passes reach beyond the application's final target (a 640x480 shadow map beside
    # a 320x240 frame) is simulated on the larger grid; the final pass's area is its top-left corner.
    if sim.shape == ids.shape and sim.shape[0] >= ref.shape[0] and sim.shape[1] >= ref.shape[1]:
        sim = sim[:ref.shape[0], :ref.shape[1]]
        ids = ids[:ref.shape[0], :ref.shape[1]]
    if ref.shape != sim.shape or ref.shape != ids.shape:
        print("%s: sizes differ: reference %s, color.png %s, triangle_id.png %s" % (PROG, ref.shape, sim.shape,
                                                                                   ids.shape), file=sys.stderr)
        return 2
    ref_cov, how = reference_coverage(frame, a.capture_dir, ref)
    if ref_cov is None:
        print("%s: %s" % (PROG, how), file=sys.stderr)
        return 2
    sim_cov = np.any(ids != 0, axis=2)
    total = ref_cov.size
    both = ref_cov & sim_cov
    print("frame %dx%d, %d draws in %d passes" % (ref.shape[1], ref.shape[0],
                                                 sum(len(p["draws"]) for p in frame["passes"]), len(frame["passes"])))
    print("coverage: %d of %d pixels agree (%.2f%%); covered: reference %d, simulated %d, both %d (reference: %s)"
          % ((ref_cov == sim_cov).sum(), total, 100.0 * (ref_cov == sim_cov).mean(), ref_cov.sum(), sim_cov.sum(),
             both.sum(), how))
    samples = frame.get("pixel_history", {}).get("samples", [])
    if samples:
        pairs = []
        for x, y, ev, prim in samples:
            sid = tuple(ids[y, x])
            pairs.append(((ev, prim) if ev >= 0 else None, sid if any(sid) else None))
        r2s = collections.defaultdict(collections.Counter)
        s2r = collections.defaultdict(collections.Counter)
        for r, s in pairs:
            if r and s:
                r2s[r][s] += 1
                s2r[s][r] += 1
        covered = sum(1 for r, s in pairs if r and s)
        # A match: the captured triangle and the simulated one are each the other's most frequent
        # partner (one-to-one). An instanced draw's captured triangle is its primitive within the
        # instance (gl_PrimitiveID restarts per instance), which the simulator draws once per
        # instance under distinct ids: there the simulated triangle's partner must be it.
        instanced = {d["event"] for p in frame["passes"] for d in p["draws"] if d.get("instances", 1) > 1}
        match = sum(1 for r, s in pairs if r and s and s2r[s].most_common(1)[0][0] == r
                    and (r[0] in instanced or r2s[r].most_common(1)[0][0] == s))
        cov_agree = sum(1 for r, s in pairs if (r is None) == (s is None))
        print("sampled pixels (%s, every %dth): %d; coverage agrees at %d; covered in both %d, "
              "triangle matches at %d (%.2f%%); %d captured triangles seen, %d simulated"
              % ("RenderDoc pixel history" if frame["pixel_history"].get("method", "pixelhistory") == "pixelhistory"
                 else "draw ids read back, triangles from the clip positions", frame["pixel_history"]["step"], len(pairs), cov_agree, covered, match,
                 100.0 * match / max(covered, 1), len(r2s), len(s2r)))
    if both.any():
        diff = np.abs(ref - sim)[both].mean()
        print("colour: mean absolute difference %.1f of 255 over the %d pixels covered in both" % (diff, both.sum()))
    if a.out:
        gap = np.full((ref.shape[0], 4, 3), 255, dtype=np.int32)
        Image.fromarray(np.concatenate([ref, gap, sim, gap, ids], axis=1).astype(np.uint8)).save(a.out)
        print("wrote %s (application | simulated colour | simulated triangles)" % a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
