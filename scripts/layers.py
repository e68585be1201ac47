#!/usr/bin/env python3
"""Check and draw the layering of lib/ from its #include lines.

Every folder under lib/ is on the include path, so the library's own
headers are included by bare name ("occupancy.h") and a name resolves to
the folder whose directory holds that header.  lib/layers.txt lists the
folders bottom first; a folder may include only from itself and from the
folders listed before it.

  scripts/layers.py check
      Exit 1 and list every problem: an include from a folder above, a
      quoted include that names no header or names headers in two places,
      a folder missing from lib/layers.txt or listed but absent, and a
      folder holding more than a fifth of the library's lines.

  scripts/layers.py graph [--bottom-up]
      Print the picture of the layers: each folder with its description,
      its size and the folders it actually includes from.

  scripts/layers.py graph --update docs/architecture.md
  scripts/layers.py graph --check docs/architecture.md
      Rewrite, or compare, the picture between the lines
      <!-- layers:begin --> and <!-- layers:end --> of a Markdown file.

Only `#include "..."` counts (angle brackets are system headers), outside
comments.  The public headers nerf.h, nerf_version.h and nerf_config.h, and
any header not inside a folder of lib/ (lib/*.h, include/), are outside the
layers and may be included from anywhere.  Standard library only.
"""

import argparse
import difflib
import os
import re
import sys
import textwrap

# Public and generated headers every layer may include.
OUTSIDE = ("nerf.h", "nerf_version.h", "nerf_config.h")
# Files whose lines and includes are counted.
SOURCE_EXT = (".c", ".h")
BEGIN = "<!-- layers:begin -->"
END = "<!-- layers:end -->"
# Inside width of the picture's boxes.
WIDTH = 70

INCLUDE_RE = re.compile(r'^[ \t]*#[ \t]*include[ \t]*"([^"\n]+)"', re.M)
NAME_RE = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")


class Layers:
    """The folder order read from lib/layers.txt."""

    def __init__(self, path, shown):
        self.path = path
        self.shown = shown      # the path as messages name it
        self.names = []         # bottom first
        self.desc = {}
        self.line_of = {}       # folder -> line number in the file
        self.errors = []

    def index(self, folder):
        return self.names.index(folder) if folder in self.names else None


def read_layers(path, shown):
    layers = Layers(path, shown)
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        layers.errors.append("%s: cannot read the layer list: %s"
                             % (shown, e.strerror))
        return layers
    for number, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split(None, 1)
        name = parts[0].rstrip("/")
        desc = parts[1].strip() if len(parts) > 1 else ""
        if not NAME_RE.match(name):
            layers.errors.append("%s:%d: '%s' is not a folder name"
                                 % (shown, number, parts[0]))
            continue
        if name in layers.desc:
            layers.errors.append("%s:%d: folder %s is listed twice (first on "
                                 "line %d)" % (shown, number, name,
                                               layers.line_of[name]))
            continue
        layers.names.append(name)
        layers.desc[name] = desc
        layers.line_of[name] = number
    if not layers.names and not layers.errors:
        layers.errors.append("%s: lists no folders" % shown)
    return layers


def strip_comments(text):
    """The text with C comments blanked out, newlines and literals kept."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == "/" and text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            out.append("".join(ch if ch == "\n" else " "
                               for ch in text[i:end]))
            i = end
        elif c == "/" and text.startswith("//", i):
            # A line comment runs to a newline that no backslash escapes.
            j = i
            while j < n and text[j] != "\n":
                j += 2 if text[j] == "\\" and j + 1 < n else 1
            out.append("".join(ch if ch == "\n" else " "
                               for ch in text[i:j]))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(text[i:j])
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


class Tree:
    """The C sources under lib/ and what their quoted includes resolve to."""

    def __init__(self, root):
        self.root = root
        self.lib = os.path.join(root, "lib")
        self.include = os.path.join(root, "include")
        self.files = []         # paths relative to root, '/'-separated
        self.lines = {}         # file -> line count
        self.includes = {}      # file -> [(line, name)]
        self.folders = []       # sorted folders under lib/ holding sources
        self._scan()

    def _scan(self):
        if not os.path.isdir(self.lib):
            raise SystemExit("layers.py: %s is not a directory" % self.lib)
        folders = set()
        for dirpath, dirnames, filenames in os.walk(self.lib):
            dirnames[:] = sorted(d for d in dirnames if not d.startswith("."))
            for name in sorted(filenames):
                if not name.endswith(SOURCE_EXT):
                    continue
                full = os.path.join(dirpath, name)
                rel = os.path.relpath(full, self.root).replace(os.sep, "/")
                with open(full, "rb") as f:
                    text = f.read().decode("utf-8", "replace")
                self.files.append(rel)
                self.lines[rel] = len(text.splitlines())
                self.includes[rel] = scan_includes(text)
                folder = folder_of(rel)
                if folder is not None:
                    folders.add(folder)
        self.files.sort()
        self.folders = sorted(folders)

    def total_lines(self):
        return sum(self.lines.values())

    def folder_lines(self, folder):
        return sum(n for f, n in self.lines.items() if folder_of(f) == folder)

    def folder_files(self, folder):
        return sum(1 for f in self.files if folder_of(f) == folder)

    def resolve(self, including, name):
        """The distinct files a quoted include can mean, relative to root.

        The compiler looks beside the including file first, then along the
        include path: every folder of lib/, lib/ itself and include/.  A
        name found in more than one of them is ambiguous even where the
        compiler would pick the first, because which one a file gets then
        depends on where the file sits.
        """
        here = os.path.dirname(os.path.join(self.root, including))
        dirs = [here] + [os.path.join(self.lib, f) for f in self.folders]
        dirs += [self.lib, self.include]
        found = []
        for d in dirs:
            path = os.path.normpath(os.path.join(d, name))
            if os.path.isfile(path):
                rel = os.path.relpath(path, self.root).replace(os.sep, "/")
                if rel not in found:
                    found.append(rel)
        return found


def scan_includes(text):
    """[(line number, name)] of the quoted includes outside comments."""
    clean = strip_comments(text)
    result = []
    for m in INCLUDE_RE.finditer(clean):
        result.append((clean.count("\n", 0, m.start()) + 1, m.group(1)))
    return result


def folder_of(rel):
    """The folder of lib/ a root-relative path sits in, or None."""
    parts = rel.split("/")
    if len(parts) >= 3 and parts[0] == "lib":
        return parts[1]
    return None


def edges(tree):
    """Resolved includes and the problems met resolving them.

    Returns ({folder: {folder it includes from}}, [(file, line, message)]).
    """
    uses = {f: set() for f in tree.folders}
    problems = []
    for rel in tree.files:
        for line, name in tree.includes[rel]:
            if name in OUTSIDE:
                continue
            found = sorted(tree.resolve(rel, name))
            if not found:
                problems.append((rel, line, 'includes "%s", which is not a '
                                 "header under lib/ or include/" % name))
                continue
            if len(found) > 1:
                where = ", ".join(
                    "%s (folder %s)" % (p, folder_of(p)) if folder_of(p)
                    else p for p in found)
                problems.append((rel, line, 'includes "%s", which is '
                                 "ambiguous: it names %s" % (name, where)))
                continue
            src, dst = folder_of(rel), folder_of(found[0])
            if src is not None and dst is not None and src != dst:
                uses[src].add(dst)
    return uses, problems


def check(tree, layers):
    """Every problem, as lines of text, in a fixed order."""
    out = list(layers.errors)
    listed = set(layers.names)
    for f in tree.folders:
        if f not in listed:
            out.append("lib/%s/: folder is not listed in %s (add it where it "
                       "belongs in the order)" % (f, layers.shown))
    for f in layers.names:
        if f not in tree.folders:
            out.append("%s:%d: lists folder %s, but lib/%s/ holds no C "
                       "sources" % (layers.shown, layers.line_of[f], f, f))
    _, problems = edges(tree)
    for rel in tree.files:
        g = folder_of(rel)
        for line, name in tree.includes[rel]:
            if name in OUTSIDE or g is None:
                continue
            found = tree.resolve(rel, name)
            if len(found) != 1:
                continue
            f = folder_of(found[0])
            if f is None or f == g:
                continue
            if g not in listed:
                msg = ('includes "%s" from folder %s, but folder %s is not '
                       "listed in %s" % (name, f, g, layers.shown))
            elif f not in listed:
                msg = ('includes "%s" from folder %s, which is not listed in '
                       "%s (folder %s is)" % (name, f, layers.shown, g))
            elif layers.index(f) > layers.index(g):
                msg = ('includes "%s" from folder %s, which is above folder '
                       "%s in %s" % (name, f, g, layers.shown))
            else:
                continue
            problems.append((rel, line, msg))
    for rel, line, msg in sorted(problems):
        out.append("%s:%d: %s" % (rel, line, msg))
    total = tree.total_lines()
    for f in tree.folders:
        n = tree.folder_lines(f)
        if 5 * n > total:
            out.append("lib/%s/: %s of the library's %s lines (%.1f%%) is "
                       "more than a fifth (%s lines)"
                       % (f, thousands(n), thousands(total),
                          100.0 * n / total, thousands(total // 5)))
    return out


def thousands(n):
    return "{:,}".format(n)


def box_rule(title="", right="", corner="+"):
    """A horizontal rule of the picture, with a title left and a note right."""
    left = "-- %s " % title if title else ""
    right = " %s --" % right if right else ""
    fill = WIDTH - len(left) - len(right)
    return corner + left + "-" * max(fill, 1) + right + corner


def box_text(text, indent=""):
    """Lines of text wrapped into the box."""
    lines = textwrap.wrap(text, WIDTH - 2, initial_indent=indent,
                          subsequent_indent=indent + "   ",
                          break_on_hyphens=False)
    return ["| %-*s |" % (WIDTH - 2, s) for s in lines]


def graph(tree, layers, top_down=True):
    """The picture of the layers, as one string."""
    uses, _ = edges(tree)
    listed = [f for f in layers.names if f in tree.folders]
    unlisted = [f for f in tree.folders if f not in layers.names]
    # Unlisted folders go on top, where nothing may include from them.
    order = unlisted + listed[::-1] if top_down else listed + unlisted
    rank = {f: i for i, f in enumerate(listed)}
    total = tree.total_lines()
    out = []
    if top_down:
        out.append("lib/, top layer first: each folder may include only "
                   "from the folders below it.")
    else:
        out.append("lib/, bottom layer first: each folder may include only "
                   "from the folders before it.")
    out.append("")
    notes = set()
    for i, f in enumerate(order):
        n = tree.folder_lines(f)
        files = tree.folder_files(f)
        # Files, not lines: the picture changes with the structure, not
        # with every edit.
        size = "%d file%s" % (files, "" if files == 1 else "s")
        if 5 * n > total:
            size += " [over 1/5]"
            notes.add("over")
        title = f if f in rank else f + " [not listed]"
        if f not in rank:
            notes.add("unlisted")
        out.append(box_rule(title, size))
        desc = layers.desc.get(f) or ""
        if desc:
            out.extend(box_text(desc))
        # Includes from, nearest layer first in the picture's direction.
        def key(g):
            if g in rank:
                return (0, -rank[g] if top_down else rank[g], g)
            return (1, 0, g)
        names = []
        for g in sorted(uses[f], key=key):
            if f in rank and g in rank and rank[g] > rank[f]:
                names.append(g + " [upward]")
                notes.add("upward")
            elif g not in rank:
                names.append(g + " [not listed]")
                notes.add("unlisted")
            else:
                names.append(g)
        if names:
            out.extend(box_text("includes from: " + ", ".join(names)))
        else:
            out.extend(box_text("includes from no other folder"))
    out.append(box_rule())
    out.append("")
    out.append("%d folders under lib/; no folder may hold more than a "
               "fifth of the library's lines (`layers.py check` counts "
               "them)." % len(tree.folders))
    absent = [f for f in layers.names if f not in tree.folders]
    if absent:
        out.append("Listed in lib/layers.txt but not under lib/: %s."
                   % ", ".join(absent))
    if "upward" in notes:
        out.append("[upward]: an include from a folder above, which "
                   "`layers.py check` rejects.")
    if "unlisted" in notes:
        out.append("[not listed]: a folder missing from lib/layers.txt.")
    if "over" in notes:
        out.append("[over 1/5]: a folder holding more than a fifth of the "
                   "lines.")
    return "\n".join(wrap_plain(out)) + "\n"


def wrap_plain(lines):
    """Wrap the lines outside the boxes to the picture's width."""
    result = []
    for line in lines:
        if line.startswith(("+", "|")) or len(line) <= WIDTH + 2:
            result.append(line)
        else:
            result.extend(textwrap.wrap(line, WIDTH + 2,
                                        break_on_hyphens=False))
    return result


def doc_block(picture):
    return ("<!-- generated by scripts/layers.py graph --update; "
            "do not edit by hand -->\n```text\n" + picture + "```\n")


def split_doc(text, doc):
    """(before, block, after) around the markers, or exit with a message."""
    b = text.find(BEGIN)
    e = text.find(END)
    if b < 0 or e < 0 or e < b or text.find(BEGIN, b + 1) >= 0:
        raise SystemExit("layers.py: %s needs one line %s and, after it, "
                         "one line %s" % (doc, BEGIN, END))
    start = text.index("\n", b) + 1
    return text[:start], text[start:e], text[e:]


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(
        description="Check and draw the layering of lib/.")
    p.add_argument("mode", choices=("check", "graph"))
    p.add_argument("--root", default=os.path.dirname(here),
                   help="the source tree (default: this script's parent)")
    p.add_argument("--layers",
                   help="the layer list (default: ROOT/lib/layers.txt)")
    p.add_argument("--bottom-up", action="store_true",
                   help="graph: draw the bottom layer first")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--update", metavar="DOC",
                   help="graph: rewrite the picture between the markers "
                   "of DOC")
    g.add_argument("--check", metavar="DOC",
                   help="graph: exit 1 if the picture in DOC is out of date")
    args = p.parse_args(argv)

    root = os.path.abspath(args.root)
    path = args.layers or os.path.join(root, "lib", "layers.txt")
    shown = os.path.relpath(os.path.abspath(path), root).replace(os.sep, "/")
    if shown.startswith(".."):
        shown = path
    layers = read_layers(path, shown)
    tree = Tree(root)

    if args.mode == "check":
        if args.update or args.check or args.bottom_up:
            p.error("--update, --check and --bottom-up go with graph")
        problems = check(tree, layers)
        for line in problems:
            print(line)
        if problems:
            print("layers.py: %d problem%s in lib/ (the order is in %s)"
                  % (len(problems), "" if len(problems) == 1 else "s",
                     layers.shown))
            return 1
        n = sum(len(v) for v in tree.includes.values())
        print("layers.py: lib/ keeps its layers: %d folders, %d files, %d "
              "quoted includes" % (len(tree.folders), len(tree.files), n))
        return 0

    if layers.errors:
        for line in layers.errors:
            print(line, file=sys.stderr)
        return 2
    picture = graph(tree, layers, top_down=not args.bottom_up)
    if not args.update and not args.check:
        sys.stdout.write(picture)
        return 0
    doc = args.update or args.check
    with open(doc, encoding="utf-8") as f:
        text = f.read()
    before, block, after = split_doc(text, doc)
    want = doc_block(picture)
    if args.update:
        if block != want:
            with open(doc, "w", encoding="utf-8") as f:
                f.write(before + want + after)
            print("layers.py: updated the picture in %s" % doc)
        return 0
    if block == want:
        print("layers.py: the picture in %s is up to date" % doc)
        return 0
    sys.stdout.writelines(difflib.unified_diff(
        block.splitlines(True), want.splitlines(True),
        doc + " (now)", "scripts/layers.py graph (wanted)"))
    rel = os.path.relpath(os.path.abspath(doc), root).replace(os.sep, "/")
    rel = doc if rel.startswith("..") else rel
    print("layers.py: the picture of the layers in %s is out of date with "
          "lib/; regenerate it with: scripts/layers.py graph --update %s"
          % (rel, rel))
    return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
