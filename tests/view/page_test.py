"""The page `rtcd run --view` writes, opened from file:// in headless Chromium
(software WebGL, SwiftShader): the default scene's bodies drawn where the
scene puts them at step 0 and where they fell at the last step, the contact
overlay's colour when it is on, and a click on a body that names it.

Usage: page_test.py RTCD WORK_DIR [SCREENSHOT]
SCREENSHOT: where to keep the contact screenshot; its figures (the folder's
size, the time to the first frame, ...) go beside it as SCREENSHOT.json.
"""

import json
import os
import re
import shutil
import subprocess
import sys
import time
import unittest

from PIL import Image

RTCD, WORK = sys.argv[1], sys.argv[2]
FIGURES = {}
SIZE = (960, 600)
BACKGROUND = (0xEE, 0xF0, 0xF3)


BAR = 64  # the timeline under the view
DUMP_EXTRA = None  # how much taller a --dump-dom window must be to show the screenshot's view


def chromium(url, height, *args):
    profile = os.path.join(WORK, "chromium-profile")
    command = ["chromium", "--headless", "--no-sandbox", "--use-gl=swiftshader", "--enable-unsafe-swiftshader",
               "--hide-scrollbars", "--window-size=%d,%d" % (SIZE[0], height), "--user-data-dir=" + profile, *args,
               url]
    return subprocess.run(command, capture_output=True, text=True, timeout=300, check=True)


def screenshot(url, name):
    path = os.path.join(WORK, name)
    chromium(url, SIZE[1], "--screenshot=" + path)
    return Image.open(path).convert("RGB")


def probe(url):
    """The page's state after it drew, read from its DOM. Headless Chromium
    gives --dump-dom a shorter view than --screenshot for the same window,
    so the window is made taller until the two views are the same size."""
    global DUMP_EXTRA
    if DUMP_EXTRA is None:
        DUMP_EXTRA = 0
        state, _ = probe(url)
        DUMP_EXTRA = SIZE[1] - BAR - state["canvas"][1]
    dom = chromium(url, SIZE[1] + DUMP_EXTRA, "--dump-dom").stdout
    found = re.search(r'<pre id="probe">(.*?)</pre>', dom, re.S)
    assert found and found.group(1), "the page drew nothing: " + dom[-2000:]
    state = json.loads(found.group(1).replace("&quot;", '"'))
    LEGEND[:] = state["legend"]
    if DUMP_EXTRA:
        assert state["canvas"] == [SIZE[0], SIZE[1] - BAR], state["canvas"]
    return state, dom


def near(a, b, tolerance=24):
    return all(abs(x - y) <= tolerance for x, y in zip(a, b))


def ground_colour(image):
    """The ground is one flat square, lit the same all over: the commonest
    colour that is not the background."""
    counts = {}
    for p in image.crop((0, 0, SIZE[0], SIZE[1] - BAR)).getdata():
        if not near(p, BACKGROUND, 6):
            counts[p] = counts.get(p, 0) + 1
    return max(counts, key=counts.get)


LEGEND = [0, 0, 0, 0]  # the legend's box over the view (the probe says where)


def body_pixels(image, ground):
    """Pixels of the view (above the timeline bar, the legend left out) that
    are neither the background nor the ground."""
    width, height = image.size
    data = image.load()
    out = []
    for y in range(0, height - BAR):
        for x in range(width):
            if LEGEND[0] - 2 <= x <= LEGEND[2] + 2 and LEGEND[1] - 2 <= y <= LEGEND[3] + 2:
                continue
            p = data[x, y]
            if not near(p, BACKGROUND, 6) and not near(p, ground, 10):
                out.append((x, y))
    return out


class Page(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        shutil.rmtree(WORK, ignore_errors=True)
        os.makedirs(WORK)
        cls.run_dir = os.path.join(WORK, "run")
        started = time.time()
        subprocess.run([RTCD, "run", "--view", "--no-plots", "--out", cls.run_dir], check=True,
                       stdout=subprocess.DEVNULL)
        FIGURES["seconds_run_and_page"] = round(time.time() - started, 1)
        print("run and page: %.1f s" % FIGURES["seconds_run_and_page"])
        cls.page = os.path.join(cls.run_dir, "view")
        cls.index = "file://" + os.path.abspath(os.path.join(cls.page, "index.html"))
        with open(os.path.join(cls.page, "data", "scene.js")) as f:
            text = f.read()
        cls.scene = json.loads(text[text.index("=") + 1:text.rindex(";")])
        cls.last = cls.scene["steps"] - 1

    @classmethod
    def tearDownClass(cls):
        if len(sys.argv) > 3:
            with open(os.path.splitext(sys.argv[3])[0] + ".json", "w") as f:
                json.dump(FIGURES, f, indent=2)

    def test_folder_is_small_enough(self):
        size = sum(os.path.getsize(os.path.join(d, f)) for d, _, files in os.walk(self.page) for f in files)
        FIGURES["folder_bytes"] = size
        FIGURES["files"] = {os.path.relpath(os.path.join(d, f), self.page): os.path.getsize(os.path.join(d, f))
                            for d, _, files in os.walk(self.page) for f in files}
        print("page folder: %.1f MB" % (size / 1e6))
        self.assertLessEqual(size, 32e6)

    def test_bodies_where_the_scene_puts_them_and_where_they_fell(self):
        first, _ = probe(self.index + "#step=0&contacts=0")
        last, _ = probe(self.index + "#step=%d&contacts=0" % self.last)
        FIGURES["first_frame_ms"] = round(first["first_frame_ms"])
        FIGURES["bodies_drawn"] = first["bodies_drawn"]
        print("first frame: %.0f ms" % first["first_frame_ms"])
        self.assertLess(first["first_frame_ms"], 120000)
        self.assertEqual(first["bodies_drawn"], 512)
        self.assertEqual(last["bodies_drawn"], 512)
        self.assertEqual(first["contacts_drawn"], 0)
        shots = {}
        for name, at, box in (("first", 0, first["centres_box"]), ("last", self.last, last["centres_box"])):
            image = screenshot(self.index + "#step=%d&contacts=0" % at, "step_%s.png" % name)
            self.assertEqual(image.size, SIZE)
            ground = ground_colour(image)
            pixels = body_pixels(image, ground)
            self.assertGreater(len(pixels), 5000, name)
            # Body pixels lie around the bodies' centres on the screen (a
            # body's radius beside them), and most of the box is covered.
            margin = 60
            inside = [p for p in pixels if box[0] - margin <= p[0] <= box[2] + margin and
                      box[1] - margin <= p[1] <= box[3] + margin]
            self.assertGreater(len(inside), 0.95 * len(pixels), name)
            shots[name] = (image, pixels)
        # They fell: the bodies' pixels sit lower on the screen at the end,
        # and the two images differ there.
        mean_y = {n: sum(y for _, y in p) / len(p) for n, (_, p) in shots.items()}
        self.assertGreater(mean_y["last"], mean_y["first"] + 40)
        self.assertGreater(last["centres_box"][3], first["centres_box"][3])
        a, b = shots["first"][0].load(), shots["last"][0].load()
        changed = sum(1 for x, y in shots["last"][1] if not near(a[x, y], b[x, y], 6))
        self.assertGreater(changed, 0.5 * len(shots["last"][1]))

    def test_contact_overlay_adds_its_colour(self):
        off = screenshot(self.index + "#step=%d&contacts=0" % self.last, "contacts_off.png")
        on = screenshot(self.index + "#step=%d" % self.last, "contacts_on.png")
        state, _ = probe(self.index + "#step=%d" % self.last)
        self.assertGreater(state["contacts_drawn"], 100)
        a, b = off.load(), on.load()
        # The overlay's ramp runs from yellow through red to purple: little
        # green and blue below red.
        overlay = 0
        for y in range(SIZE[1] - BAR):
            for x in range(SIZE[0]):
                p, q = a[x, y], b[x, y]
                if not near(p, q, 30) and q[0] > 150 and q[2] < 120:
                    overlay += 1
        FIGURES["overlay_pixels"] = overlay
        FIGURES["contacts_drawn_last_step"] = state["contacts_drawn"]
        print("overlay pixels: %d" % overlay)
        self.assertGreater(overlay, 200)
        if len(sys.argv) > 3:
            on.save(sys.argv[3])

    def test_click_on_a_body_names_it(self):
        image = screenshot(self.index + "#step=%d&contacts=0" % self.last, "click.png")
        ground = ground_colour(image)
        pixels = body_pixels(image, ground)
        cx = sum(x for x, _ in pixels) / len(pixels)
        cy = sum(y for _, y in pixels) / len(pixels)
        x, y = min(pixels, key=lambda p: (p[0] - cx) ** 2 + (p[1] - cy) ** 2)
        state, dom = probe(self.index + "#step=%d&contacts=0&click=%d,%d" % (self.last, x, y))
        labels = set(self.scene["labels"]) - {"ground"}
        self.assertIn(state["picked"], labels)
        self.assertIn("body %d: %s" % (self.scene["labels"].index(state["picked"]), state["picked"]), dom)
        self.assertIn("shape: ", dom)
        # The background names nothing.
        state, _ = probe(self.index + "#step=0&contacts=0&click=3,3")
        self.assertIsNone(state["picked"])


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
