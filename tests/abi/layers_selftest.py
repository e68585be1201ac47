#!/usr/bin/env python3
"""Tests of scripts/layers.py on small synthetic trees.

The layer check and the docs check guard lib/ only if they can fail, so
this builds trees in a temporary folder, breaks them one way at a time and
expects each break to be reported with the file, line, header and folders.

usage: layers_selftest.py [path/to/scripts/layers.py]
"""

import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = (sys.argv[1] if len(sys.argv) > 1 else
          os.path.join(HERE, "..", "..", "scripts", "layers.py"))

LAYERS = """\
# bottom first
base      the ground floor
middle    uses base
# a comment between entries
top       uses both   # and a trailing comment
"""

# Five folders of ten or twenty lines and forty lines outside them: no
# folder holds more than a fifth of the 110.
CLEAN = {
    "lib/layers.txt": LAYERS + "side1  filler\nside2  filler\n",
    "lib/base/base.h": '#include "nerf.h"\n',
    "lib/base/base.c": '#include "base.h"\n#include <stdio.h>\n',
    "lib/middle/middle.h": '#include "base.h"\n',
    "lib/middle/middle.c": ('#include "middle.h"\n'
                            '/* #include "top.h" in a comment */\n'
                            '// #include "top.h" in a line comment\n'
                            'static const char *s = "#include \\"top.h\\"";\n'
                            '#include "nerf_config.h"\n'),
    "lib/top/top.c": ('#include "middle.h"\n'
                      '  #  include "base.h"\n'
                      '#include "private.h"\n'),
    # Lines outside the folders count towards the library's total.
    "lib/private.h": "/* outside the layers */\n" + "\n" * 39,
    "lib/side1/a.c": "",
    "lib/side2/b.c": "",
    "include/nerf.h": "",
    "docs/arch.md": ("# Title\n\n<!-- layers:begin -->\nstale\n"
                     "<!-- layers:end -->\n\nAfter.\n"),
}


def pad(files):
    """Every source file padded to ten lines."""
    out = dict(files)
    for path, text in files.items():
        if path.endswith((".c", ".h")):
            n = len(text.splitlines())
            out[path] = text + "\n" * (10 - n)
    return out


def write(root, files):
    for path, text in files.items():
        full = os.path.join(root, path)
        os.makedirs(os.path.dirname(full), exist_ok=True)
        with open(full, "w") as f:
            f.write(text)


def run(root, *args):
    r = subprocess.run([sys.executable, SCRIPT] + list(args) +
                       ["--root", root], stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, universal_newlines=True)
    return r.returncode, r.stdout


failures = []


def expect(name, root, code, needles, *args):
    got, out = run(root, *(args or ("check",)))
    missing = [n for n in needles if n not in out]
    if got != code or missing:
        failures.append("%s: exit %d (wanted %d), missing %r in:\n%s"
                        % (name, got, code, missing, out))
    else:
        print("ok: %s" % name)
    return out


def case(name, change, code, needles, *args):
    with tempfile.TemporaryDirectory() as root:
        files = dict(CLEAN)
        files.update(change)
        write(root, pad(files))
        return expect(name, root, code, needles, *args)


case("clean tree passes", {}, 0, ["keeps its layers"])
case("upward include", {"lib/base/base.c": '\n#include "middle.h"\n'}, 1,
     ['lib/base/base.c:2: includes "middle.h" from folder middle, which is '
      "above folder base in lib/layers.txt"])
case("unknown header", {"lib/middle/middle.c": '#include "nowhere.h"\n'}, 1,
     ['lib/middle/middle.c:1: includes "nowhere.h", which is not a header'])
case("ambiguous header", {"lib/top/base.h": ""}, 1,
     ['lib/middle/middle.h:1: includes "base.h", which is ambiguous: it '
      "names lib/base/base.h (folder base), lib/top/base.h (folder top)"])
case("folder missing from the list", {"lib/extra/x.c": '#include "base.h"'},
     1, ["lib/extra/: folder is not listed in lib/layers.txt",
         'lib/extra/x.c:1: includes "base.h" from folder base, but folder '
         "extra is not listed in lib/layers.txt"])
case("include from an unlisted folder",
     {"lib/extra/x.h": "", "lib/top/top.c": '#include "x.h"'}, 1,
     ['lib/top/top.c:1: includes "x.h" from folder extra, which is not '
      "listed in lib/layers.txt (folder top is)"])
case("listed folder absent", {"lib/layers.txt": CLEAN["lib/layers.txt"] +
                              "gone  not there\n"}, 1,
     ["lib/layers.txt:8: lists folder gone, but lib/gone/ holds no C "
      "sources"])
case("folder listed twice", {"lib/layers.txt": CLEAN["lib/layers.txt"] +
                             "base\n"}, 1,
     ["lib/layers.txt:8: folder base is listed twice (first on line 2)"])
case("folder over a fifth", {"lib/top/big.c": "\n" * 30}, 1,
     ["lib/top/: 40 of the library's 140 lines (28.6%) is more than a fifth "
      "(28 lines)"])

# The picture: derived from the includes, deterministic.
out = case("graph", {}, 0, ["top layer first", "-- top --",
                            "includes from: middle, base",
                            "includes from no other folder"], "graph")
again = case("graph again", {}, 0, [], "graph")
if out != again:
    failures.append("graph: two runs differ")
case("graph marks an upward include",
     {"lib/base/base.c": '#include "middle.h"'}, 0,
     ["includes from: middle [upward]"], "graph")
case("graph bottom-up", {}, 0, ["bottom layer first"], "graph", "--bottom-up")

# The docs check: fails on a stale block, passes once updated, and leaves
# the text around the markers alone.
with tempfile.TemporaryDirectory() as root:
    write(root, pad(CLEAN))
    doc = os.path.join(root, "docs", "arch.md")
    expect("docs check fails on a stale picture", root, 1,
           ["out of date", "scripts/layers.py graph --update docs/arch.md"],
           "graph", "--check", doc)
    expect("docs update", root, 0, ["updated"], "graph", "--update", doc)
    expect("docs check passes after the update", root, 0, ["up to date"],
           "graph", "--check", doc)
    with open(doc) as f:
        text = f.read()
    if not (text.startswith("# Title\n\n<!-- layers:begin -->\n") and
            text.endswith("<!-- layers:end -->\n\nAfter.\n") and
            "-- middle --" in text):
        failures.append("docs update: unexpected result:\n" + text)
    # A line added to a file leaves the picture as it was; a new include
    # between folders makes it stale.
    with open(os.path.join(root, "lib", "top", "top.c"), "a") as f:
        f.write("\n")
    expect("docs check ignores line counts", root, 0, ["up to date"],
           "graph", "--check", doc)
    with open(os.path.join(root, "lib", "side2", "b.c"), "a") as f:
        f.write('#include "base.h"\n')
    expect("docs check fails after lib/ changes", root, 1, ["out of date"],
           "graph", "--check", doc)
    with open(doc, "w") as f:
        f.write("no markers\n")
    expect("docs check without markers", root, 1, ["<!-- layers:begin -->"],
           "graph", "--check", doc)

for f in failures:
    print("FAIL: " + f)
sys.exit(1 if failures else 0)
