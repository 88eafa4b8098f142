#!/usr/bin/env python3
"""Writes the G-MLT paper's conditions (issue 58, item 4) of the door, veach-ajar and torus
scenes into bench/gmlt/paper/ (git-ignored output): each scene at its own aspect with about
230 000 pixels (door and torus 560 x 420, veach-ajar 640 x 360), a box pixel filter (what
pmlt's and gmlt's splats are), everything else as in the source scene. veach-ajar reads its
meshes and textures from the shared folder (../shared beside the repository).

    python3 bench/gmlt/make_paper_scenes.py
"""
import os
import re

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
OUT = os.path.join(ROOT, "bench", "gmlt", "paper")
SHARED = os.path.join(ROOT, "..", "shared", "scenes", "veach-ajar")

SCENES = [
    ("door-560", os.path.join(ROOT, "scenes", "door", "door.pbrt"), 560, 420, None),
    ("torus-560", os.path.join(ROOT, "scenes", "torus-in-glass.pbrt"), 560, 420, None),
    ("veach-ajar-640", os.path.join(SHARED, "scene.pbrt"), 640, 360, SHARED),
]


def convert(text, xres, yres, assets):
    out = []
    for line in text.splitlines():
        head = line.strip().split(" ")[0]
        if head == "Film":
            line = ('Film "image" "integer xresolution" [%d] "integer yresolution" [%d] '
                    '"string filename" ["out.exr"]' % (xres, yres))
        elif head == "PixelFilter":
            line = 'PixelFilter "box"'
        elif assets and '"string filename"' in line:
            rel = os.path.relpath(assets, OUT)
            line = re.sub(r'"string filename" \[ "([^"]+)" \]',
                          lambda m: '"string filename" [ "%s/%s" ]' % (rel, m.group(1)), line)
        out.append(line)
    return "\n".join(out) + "\n"


def main():
    os.makedirs(OUT, exist_ok=True)
    with open(os.path.join(OUT, ".gitignore"), "w") as f:
        f.write("*\n")
    for name, src, xres, yres, assets in SCENES:
        if not os.path.exists(src):
            print("skipped %s: %s absent" % (name, src))
            continue
        with open(src) as f:
            text = f.read()
        with open(os.path.join(OUT, name + ".pbrt"), "w") as f:
            f.write(convert(text, xres, yres, assets))
        print("wrote", os.path.join(OUT, name + ".pbrt"))


if __name__ == "__main__":
    main()
