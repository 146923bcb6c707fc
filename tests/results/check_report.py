#!/usr/bin/env python3
"""Checks a probecomp HTML report (issue 22) against the run's JSON statistics and in a real browser.

  check_report.py REPORT.html STATS.json|- [--chromium] [--expect-tolerance] [--expect-difference]

(- for no JSON: the numbers are not compared.)

1. Self-contained: no element loads anything (no src=, href=, url(), @import, srcset, <link>, <iframe>, ...), and no
   address outside the page appears but the SVG namespace.
2. Its numbers are the JSON's: the counts by status, the trusted points' deviation (points, mean, std, min, max,
   out of tolerance), each face's row, the registration's transform, the view's characteristics (zones; with every
   point drawn, their points, min and max).
3. With --chromium: rendered by headless Chromium, offline (every host unresolvable, no proxy reachable), with no
   console message at all (the page logs nothing, so any message is an error or a failed load); the 3-D view has
   drawn every point it holds (the page marks <body data-drawn-points>); a drag turns it, the wheel zooms it and
   colouring by status (and by a characteristic, where it has them) recolours it (each changes the canvas); a
   screenshot of the view is not blank.
Prints what it checked; exits 1 on the first failure.
"""
import html.parser
import json
import os
import re
import struct
import subprocess
import sys
import tempfile
import zlib


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def ok(message):
    print("ok: " + message)


class Tables(html.parser.HTMLParser):
    """Cells of every table with an id, row by row; every attribute that could load something; the view's data."""

    def __init__(self):
        super().__init__()
        self.tables, self.loads, self.view_data = {}, [], None
        self._table, self._row, self._cell, self._script = None, None, None, None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        for name in ("src", "href", "srcset", "data", "poster", "background", "action", "formaction"):
            if name in a:
                self.loads.append("<%s %s=%r>" % (tag, name, a[name]))
        if tag in ("link", "iframe", "embed", "object", "img", "audio", "video", "source", "base"):
            self.loads.append("<%s>" % tag)
        if tag == "table" and "id" in a:
            self._table = a["id"]
            self.tables[self._table] = []
        elif tag == "tr" and self._table:
            self._row = []
            self.tables[self._table].append(self._row)
        elif tag in ("td", "th") and self._row is not None:
            self._cell = ""
        elif tag == "script":
            self._script = a.get("id", "")
            self._text = ""

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self._row.append(self._cell.strip())
            self._cell = None
        elif tag == "tr":
            self._row = None
        elif tag == "table":
            self._table = None
        elif tag == "script":
            if self._script == "view-data":
                self.view_data = json.loads(self._text)
            self._script = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data
        if self._script is not None:
            self._text += data


def close(a, b, tol, what):
    if abs(float(a) - float(b)) > tol:
        fail("%s: the report says %s, the JSON %s" % (what, a, b))


def check_self_contained(text, page):
    if page.loads:
        fail("the report loads from outside itself: " + ", ".join(page.loads[:5]))
    for pattern in (r"url\s*\(", r"@import", r"\bfetch\s*\(", r"XMLHttpRequest", r"new\s+Worker", r"import\s*\("):
        if re.search(pattern, text):
            fail("the report has %s" % pattern)
    addresses = set(re.findall(r"(?:https?|ftp|wss?)://[^\s\"'<>)]*", text))
    addresses.discard("http://www.w3.org/2000/svg")  # a namespace name, never fetched
    if addresses:
        fail("the report names addresses outside it: %s" % sorted(addresses)[:5])
    ok("self-contained (nothing loaded from outside, no address but the SVG namespace)")


def check_numbers(page, stats, expect_tolerance):
    names = ["ok", "outlier", "edge", "double-contact", "few-points", "not-on-model", "failed"]
    head, row = page.tables["counts"]
    for name, value in zip(head, row):
        want = stats["counts"]["total"] if name == "total" else stats["counts"][name]
        if int(value) != want:
            fail("count %s: the report says %s, the JSON %s" % (name, value, want))
    if head[:len(names)] != names:
        fail("the counts table's columns are %s" % head)
    ok("counts by status equal the JSON's: %s" % dict(zip(head, row)))

    head, row = page.tables["deviation"]
    d = stats["deviation"]
    if int(row[0]) != d["points"]:
        fail("trusted points: %s against %s" % (row[0], d["points"]))
    for k, name in enumerate(["mean", "std", "min", "max"], start=1):
        close(row[k], d[name], 5.1e-7, "deviation " + name)  # the report prints 6 decimals
    if expect_tolerance:
        if "out_of_tolerance" not in d or head[-1] != "out of tolerance":
            fail("a tolerance was given but the report or the JSON has no out-of-tolerance count")
        if int(row[5]) != d["out_of_tolerance"]:
            fail("out of tolerance: %s against %s" % (row[5], d["out_of_tolerance"]))
    ok("deviation of the trusted points equals the JSON's: %s" % dict(zip(head, row)))

    rows = page.tables["faces"][1:]
    faces = stats["faces"]
    if len(rows) != len(faces):
        fail("%d face rows against %d faces in the JSON" % (len(rows), len(faces)))
    for r, f in zip(rows, faces):
        fd = f["deviation"]
        if int(r[0]) != f["face"] or int(r[1]) != f["points"] or int(r[2]) != fd["points"]:
            fail("face row %s against face %s (%s points, %s ok)" % (r[:3], f["face"], f["points"], fd["points"]))
        for k, name in enumerate(["mean", "std", "min", "max"], start=3):
            close(r[k], fd[name], 5.1e-7, "face %s deviation %s" % (f["face"], name))
        if expect_tolerance and int(r[7]) != fd["out_of_tolerance"]:
            fail("face %s out of tolerance: %s against %s" % (f["face"], r[7], fd["out_of_tolerance"]))
        fitted = r[-1].startswith("fitted: ")
        if fitted != f["fitted"]:
            fail("face %s: the report says fitted %s, the JSON %s" % (f["face"], fitted, f["fitted"]))
        # A face too sparse for its NURBS but fitted as its element: "fitted as a plane: ..." and the JSON's fitted_as.
        fitted_as = r[-1][len("fitted as a "):].split(":")[0] if r[-1].startswith("fitted as a ") else None
        if fitted_as != f.get("fitted_as"):
            fail("face %s: the report says fitted as %s, the JSON %s" % (f["face"], fitted_as, f.get("fitted_as")))
    ok("%d face rows equal the JSON's faces" % len(rows))

    # Each evaluated characteristic's points in the view: its zone the JSON's, and with every point drawn, one per
    # point it used, their deviations (µm, to 0.01) spanning the JSON's min and max.
    judged = [c for c in stats.get("characteristics", []) if c["decision"] != "not-evaluated"]
    view = page.view_data.get("characteristics", [])
    if [c["name"] for c in judged] != [v["name"] for v in view]:
        fail("the view colours by %s, the JSON evaluated %s" % ([v["name"] for v in view], [c["name"] for c in judged]))
    every_point = len(page.view_data["s"]) == page.view_data["total"]
    for c, v in zip(judged, view):
        zone = [1000 * (c["outside"] - c["tolerance"]), 1000 * c["outside"]]
        if any(abs(a - b) > 0.0051 for a, b in zip(v["zone"], zone)) or not len(v["k"]) == len(v["d"]) == len(v["U"]):
            fail("characteristic %s in the view: zone %s against the JSON's %s" % (c["name"], v["zone"], zone))
        if every_point and (len(v["k"]) != c["points"] or abs(min(v["d"]) - 1000 * c["min"]) > 0.0051
                            or abs(max(v["d"]) - 1000 * c["max"]) > 0.0051):
            fail("characteristic %s in the view: %d points from %s to %s um against the JSON's %d from %s to %s mm"
                 % (c["name"], len(v["k"]), min(v["d"]), max(v["d"]), c["points"], c["min"], c["max"]))
    if view:
        ok("the view's %d characteristics have the JSON's zones%s" % (len(view), ", points, min and max" if every_point else ""))

    matrix = [float(v) for row in page.tables["transform"] for v in row]
    want = [v for row in stats["transform"] for v in row]
    for a, b in zip(matrix, want):
        close(a, b, 5.1e-10, "transform")
    ok("the registration's transform equals the JSON's")


def png_pixels(path):
    """(width, height, rows of RGB(A) bytes) of an 8-bit, non-interlaced PNG: the standard's five row filters."""
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail("%s is not a PNG" % path)
    at, idat = 8, b""
    while at < len(data):
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        chunk = data[at + 8:at + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", chunk)
        elif kind == b"IDAT":
            idat += chunk
        at += 12 + length
    if depth != 8 or interlace or colour not in (2, 6):
        fail("unexpected PNG format (depth %d, colour type %d, interlace %d)" % (depth, colour, interlace))
    bpp = 3 if colour == 2 else 4
    raw, stride, rows, prev = zlib.decompress(idat), width * bpp, [], bytearray(width * bpp)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if f == 1:
            for i in range(bpp, stride):
                line[i] = (line[i] + line[i - bpp]) & 255
        elif f == 2:
            line = bytearray((a + b) & 255 for a, b in zip(line, prev))
        elif f == 3:
            for i in range(stride):
                left = line[i - bpp] if i >= bpp else 0
                line[i] = (line[i] + ((left + prev[i]) >> 1)) & 255
        elif f == 4:
            for i in range(stride):
                a = line[i - bpp] if i >= bpp else 0
                b, c = prev[i], prev[i - bpp] if i >= bpp else 0
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return width, height, bpp, rows


def chromium(args, work):
    command = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
               "--disable-background-networking", "--disable-sync", "--disable-extensions",
               "--host-resolver-rules=MAP * ~NOTFOUND", "--proxy-server=127.0.0.1:9",
               "--user-data-dir=" + tempfile.mkdtemp(dir=work), "--enable-logging=stderr", "--v=0"] + args
    run = subprocess.run(command, capture_output=True, text=True, timeout=120)
    console = [line for line in run.stderr.splitlines() if ":CONSOLE" in line]
    return run, console


def check_in_chromium(report, page):
    work = tempfile.mkdtemp(prefix="probecomp-report-")
    url = "file://" + os.path.abspath(report)
    shot = os.path.join(work, "view.png")
    run, console = chromium(["--window-size=1000,2400", "--screenshot=" + shot, url], work)
    if run.returncode != 0 or not os.path.exists(shot):
        fail("chromium --screenshot failed: %s" % run.stderr[-500:])
    if console:
        fail("the browser's console: " + " | ".join(console[:5]))
    width, height, bpp, rows = png_pixels(shot)
    # The view's canvas: the box drawn by its 1-pixel #ccc border (the longest runs of that grey).
    border = (204, 204, 204)
    def is_border(line, x):
        return tuple(line[x * bpp:x * bpp + 3]) == border
    edges = [y for y in range(height) if sum(is_border(rows[y], x) for x in range(0, width, 4)) > width // 8]
    if len(edges) < 2:
        fail("the screenshot shows no view (no canvas border found)")
    top, bottom = edges[0], edges[-1]
    xs = [x for x in range(width) if is_border(rows[top], x)]
    left, right = xs[0], xs[-1] - 130  # the colour bar's column at the right is not the map
    drawn = coloured = red = blue = 0
    for y in range(top + 2, bottom - 1):
        line = rows[y]
        for x in range(left + 2, right):
            r, g, b = line[x * bpp], line[x * bpp + 1], line[x * bpp + 2]
            if min(r, g, b) < 250:
                drawn += 1
            if max(r, g, b) - min(r, g, b) > 60:
                coloured += 1
                red += r > b + 60
                blue += b > r + 60
    area = float((bottom - top - 3) * (right - left - 2))
    if drawn < 0.01 * area or coloured < 200:
        fail("the view in the screenshot looks blank: %.2f %% of it drawn, %d coloured pixels" % (100 * drawn / area, coloured))
    ok("screenshot: the view (%dx%d pixels) is %.1f %% drawn, %d coloured pixels (%d red, %d blue)"
       % (right - left, bottom - top, 100 * drawn / area, coloured, red, blue))

    # Interaction: a copy of the report with a script that drags, wheels and switches the colouring, each of which
    # must change the picture, and hovering a labelled point names its row.
    probe = """<script>
window.addEventListener("load", () => {
  const c = document.getElementById("view"), seen = [c.toDataURL()], marks = document.body.dataset;
  const at = (x, y) => ({clientX: c.getBoundingClientRect().left + x, clientY: c.getBoundingClientRect().top + y,
                         pointerId: 1, bubbles: true, button: 0});
  const frames = (n, then) => setTimeout(then, 50 * n);
  const changed = () => { const now = c.toDataURL(), was = seen[seen.length - 1]; seen.push(now); return String(now !== was); };
  c.dispatchEvent(new PointerEvent("pointerdown", at(200, 200)));
  c.dispatchEvent(new PointerEvent("pointermove", at(260, 230)));
  c.dispatchEvent(new PointerEvent("pointerup", at(260, 230)));
  frames(2, () => {
    marks.turned = changed();
    c.dispatchEvent(new WheelEvent("wheel", {deltaY: -400, bubbles: true, cancelable: true}));
    frames(2, () => {
      marks.zoomed = changed();
      document.querySelector("input[name=colour][value=status]").click();
      marks.statusColours = changed();
      const chosen = document.querySelector("input[name=colour][value=characteristic]");
      if (chosen) {
        chosen.click();
        marks.characteristicColours = changed();
      }
      marks.probed = "yes";
    });
  });
});
</script></body>"""
    copy = os.path.join(work, "interaction.html")
    with open(copy, "w", encoding="utf-8") as out:
        out.write(open(report, encoding="utf-8").read().replace("</body>", probe, 1))
    # One launch for the page as loaded and for the interaction (the probe script waits for the load): the rendered
    # body says how many points the view drew before the probe moved it.
    run, console = chromium(["--virtual-time-budget=5000", "--dump-dom", "file://" + copy], work)
    if run.returncode != 0:
        fail("chromium --dump-dom exited %d: %s" % (run.returncode, run.stderr[-500:]))
    if console:
        fail("the browser's console: " + " | ".join(console[:5]))
    drawn = re.search(r'data-drawn-points="(\d+)"', run.stdout)
    held = len(page.view_data["s"])
    if not drawn or int(drawn.group(1)) != held:
        fail("the 3-D view did not draw its %d points (body says %s)" % (held, drawn.group(1) if drawn else "nothing"))
    ok("rendered in headless Chromium offline with no console message; the 3-D view drew its %d points" % held)
    marks = dict(re.findall(r'data-(turned|zoomed|status-colours|characteristic-colours|probed)="([a-z]+)"', run.stdout))
    want = {"turned": "true", "zoomed": "true", "status-colours": "true", "probed": "yes"}
    if page.view_data.get("characteristics"):
        want["characteristic-colours"] = "true"
    if marks != want:
        fail("the 3-D view did not answer a drag, a wheel turn and colouring by status (and characteristic): %s" % marks)
    ok("the 3-D view turns on a drag, zooms on the wheel and recolours by status%s"
       % (" and by characteristic" if "characteristic-colours" in want else ""))


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    flags = set(a for a in sys.argv[1:] if a.startswith("--"))
    if len(args) != 2:
        fail("usage: check_report.py REPORT.html STATS.json [--chromium] [--expect-tolerance] [--expect-difference]")
    text = open(args[0], encoding="utf-8").read()
    stats = None if args[1] == "-" else json.load(open(args[1]))
    page = Tables()
    page.feed(text)
    if page.view_data is None:
        fail("the report has no 3-D view data")
    check_self_contained(text, page)
    if stats is not None:
        check_numbers(page, stats, "--expect-tolerance" in flags)
    has_difference = 'id="difference"' in text
    if ("--expect-difference" in flags) != has_difference:
        fail("the CAD-minus-conventional histogram is %s" % ("there" if has_difference else "missing"))
    for figure in ("histogram",) + (("difference",) if has_difference else ()):
        if not re.search(r'<figure id="%s"><svg[^>]*>.*?<rect' % figure, text, re.S):
            fail("the %s figure has no bars" % figure)
    ok("histograms present: %s" % ("deviation and CAD-minus-conventional" if has_difference else "deviation"))
    if "--chromium" in flags:
        check_in_chromium(args[0], page)
    print("report %s: %d bytes" % (args[0], len(text.encode("utf-8"))))


if __name__ == "__main__":
    main()
