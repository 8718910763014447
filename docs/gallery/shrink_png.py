#!/usr/bin/env python3
"""Makes the gallery's screenshots smaller: each PNG given is rewritten in place as 8-bit RGB with
its channels rounded to multiples of 8 (a change the eye does not see on a screenshot; meshes and
shading otherwise cost many distinct colours), then compressed with Pillow's optimizer. About a
third smaller on the reports' screenshots. Needs Pillow (Debian: python3-pil, which matplotlib
brings):  docs/gallery/shrink_png.py FILE.png..."""
import sys

from PIL import Image


def shrink(path):
    with Image.open(path) as image:
        rgb = image.convert("RGB")
    rgb.point(lambda value: value & ~7).save(path, optimize=True)


if __name__ == "__main__":
    for name in sys.argv[1:]:
        shrink(name)
