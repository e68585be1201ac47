"""The binding against nerf.h itself: every public function, struct, field
and constant the header declares must be in the binding (constants as
attributes of the nerf module named without NERF_), with the same types
and values.

Usage: test_header.py NERF_H

test_layout.py compares sizes and offsets with what the compiler makes of
the structs it lists; this test reads the header, so that what nobody
listed (a new function, struct, field or constant) is seen too, and so
that types agree beyond their size: signedness, float or integer, what a
pointer points to, a callback's prototype.
"""

import ctypes
import re
import sys
import unittest

import _support  # noqa: F401  (skips under sanitizers, finds nerf)
import nerf
from nerf import _capi, structs

HEADER = None

# C scalar types and the ctypes type each must be mirrored by.
SCALARS = {
    "int": ctypes.c_int, "int32_t": ctypes.c_int32,
    "unsigned": ctypes.c_uint, "uint32_t": ctypes.c_uint32,
    "uint64_t": ctypes.c_uint64, "size_t": ctypes.c_size_t,
    "uint8_t": ctypes.c_uint8, "float": ctypes.c_float,
    "double": ctypes.c_double, "char": ctypes.c_char,
}

def strip_comments(text):
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r"//[^\n]*", " ", text)


def split_top(text, sep):
    """text split at sep outside parentheses and brackets."""
    parts, depth, cur = [], 0, ""
    for ch in text:
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        if ch == sep and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    if cur.strip():
        parts.append(cur)
    return [p.strip() for p in parts if p.strip()]


class Header:
    """What nerf.h declares: constants, typedefs, structs, functions."""

    def __init__(self, path):
        with open(path, encoding="utf-8") as f:
            raw = f.read()
        text = strip_comments(raw.replace("\\\n", " "))
        self.constants = {}      # name: value
        self.callbacks = {}      # typedef name: ("func", ret, [args])
        self.structs = {}        # name: [(field, type), ...]
        self.opaque = set()      # handle names
        self.enums = set()       # enum type names (int-sized)
        self.functions = {}      # name: (ret, [args])
        for m in re.finditer(r"^\s*#\s*define\s+(NERF_\w+)[ \t]+([^\n]+)$",
                             text, re.M):
            value = self.number(m.group(2))
            if value is not None:
                self.constants[m.group(1)] = value
        for m in re.finditer(r"typedef\s+enum\s+(\w+)\s*\{(.*?)\}\s*(\w+)\s*;",
                             text, re.S):
            self.enums.add(m.group(3))
            nxt = 0
            for item in split_top(m.group(2), ","):
                name, _, value = item.partition("=")
                nxt = self.number(value) if value.strip() else nxt
                self.constants[name.strip()] = nxt
                nxt += 1
        for m in re.finditer(r"typedef\s+struct\s+(\w+)\s+(\w+)\s*;", text):
            self.opaque.add(m.group(2))
        for m in re.finditer(r"typedef\s+([^;{}]*?)\(\s*\*\s*(\w+)\s*\)"
                             r"\s*\(([^;]*)\)\s*;", text):
            self.callbacks[m.group(2)] = ("func", self.type_of(m.group(1)),
                                          self.params(m.group(3)))
        for m in re.finditer(r"typedef\s+struct\s+(\w+)\s*\{(.*?)\}\s*(\w+)"
                             r"\s*;", text, re.S):
            fields = []
            for decl in split_top(m.group(2), ";"):
                fields.extend(self.declarators(decl))
            self.structs[m.group(3)] = fields
        for m in re.finditer(r"NERF_API\s+([^;(]*?)(\w+)\s*\(([^;]*)\)\s*;",
                             text):
            self.functions[m.group(2)] = (self.type_of(m.group(1)),
                                          self.params(m.group(3)))

    def number(self, text):
        """An integer or float constant expression of the header, or None."""
        expr = text.strip()
        for name, value in sorted(self.constants.items(),
                                  key=lambda kv: -len(kv[0])):
            expr = expr.replace(name, repr(value))
        expr = re.sub(r"(?<=[0-9a-fA-F.])[uUlLfF]+\b", "", expr)
        if not re.fullmatch(r"[-+0-9a-fA-FxX.()<| eE]+", expr) or \
                not re.search(r"[0-9]", expr):
            return None
        try:
            return eval(expr, {"__builtins__": {}})  # digits and operators
        except SyntaxError:
            return None

    def type_of(self, text):
        """('ptr', t), ('array', t, n), ('name', base) or ('func', ...)."""
        text = " ".join(text.replace("const", " ").split())
        stars = text.count("*")
        t = ("name", text.replace("*", "").strip())
        for _ in range(stars):
            t = ("ptr", t)
        return t

    def params(self, text):
        text = text.strip()
        if text in ("", "void"):
            return []
        types = [self.declarators(p)[0][1] for p in split_top(text, ",")]
        # An array parameter is a pointer.
        return [("ptr", t[1]) if t[0] == "array" else t for t in types]

    def declarators(self, decl):
        """[(name, type)] of one declaration: 'float a, b', 'float c[3]',
        'void *(*alloc)(size_t size, void *user)', a parameter."""
        decl = " ".join(decl.split())
        fp = re.fullmatch(r"(.*?)\(\s*\*\s*(\w*)\s*\)\s*\((.*)\)", decl)
        if fp:
            return [(fp.group(2), ("ptr", ("func", self.type_of(fp.group(1)),
                                           self.params(fp.group(3)))))]
        parts = split_top(decl, ",")
        first = re.fullmatch(r"(.*[\s*])(\w+)\s*(\[[^\]]*\])?", parts[0])
        if first is None:  # an unnamed parameter: a type alone
            return [("", self.type_of(decl))]
        base = first.group(1).replace("*", "")
        stars = [first.group(1).count("*")]
        names = [first.group(2) + (first.group(3) or "")]
        for more in parts[1:]:
            stars.append(more.count("*"))
            names.append(more.replace("*", "").strip())
        out = []
        for n, k in zip(names, stars):
            t = self.type_of(base + "*" * k)
            arr = re.fullmatch(r"(\w+)\s*\[([^\]]*)\]", n)
            if arr:
                n, t = arr.group(1), ("array", t, self.number(arr.group(2)))
            out.append((n, t))
        return out


def struct_mirrors():
    """C struct name: its ctypes mirror, from every Structure the binding
    defines."""
    found = {}
    for module in (structs, _capi):
        for value in vars(module).values():
            if isinstance(value, type) and \
                    issubclass(value, ctypes.Structure):
                c_name = getattr(value, "_c_name_", "") or value.__name__
                found[c_name] = value
    return found


class Checker:
    def __init__(self, header):
        self.h = header
        self.mirrors = struct_mirrors()

    def agree(self, t, py):
        """Why ctypes type py does not mirror C type t (None: it does)."""
        kind = t[0]
        if kind == "name":
            name = t[1]
            if name in self.h.callbacks:
                return self.agree(("ptr", self.h.callbacks[name]), py)
            if name in self.h.enums:
                name = "int"
            if name == "void":
                return None if py is None else "%r for void" % (py,)
            if name in SCALARS:
                ok = py is SCALARS[name]
                return None if ok else "%s for %s" % (getattr(
                    py, "__name__", py), name)
            mirror = self.mirrors.get(name)
            if mirror is None:
                return "no ctypes mirror of %s" % name
            return None if py is mirror else "%s for %s" % (
                getattr(py, "__name__", py), name)
        if kind == "array":
            if not (isinstance(py, type) and issubclass(py, ctypes.Array)):
                return "%r for an array" % (py,)
            if py._length_ != t[2]:
                return "%d elements for %d" % (py._length_, t[2])
            return self.agree(t[1], py._type_)
        if kind == "ptr":
            inner = t[1]
            if inner[0] == "func":
                if not (isinstance(py, type) and
                        issubclass(py, ctypes._CFuncPtr)):
                    return "%r for a function pointer" % (py,)
                ret, args = inner[1], inner[2]
                if len(py._argtypes_) != len(args):
                    return "%d arguments for %d" % (len(py._argtypes_),
                                                    len(args))
                why = self.agree(ret, py._restype_)
                for a, p in zip(args, py._argtypes_):
                    why = why or self.agree(a, p)
                return why
            if inner == ("name", "char"):
                return None if py is ctypes.c_char_p else \
                    "%r for char *" % (py,)
            if inner == ("name", "void"):
                return None if py is ctypes.c_void_p else \
                    "%r for void *" % (py,)
            if inner[0] == "name" and inner[1] in self.h.opaque:
                ok = hasattr(py, "_type_") and \
                    getattr(py._type_, "__name__", "") == inner[1]
                return None if ok else "%r for %s *" % (py, inner[1])
            if not hasattr(py, "_type_") or py is ctypes.c_char_p or \
                    py is ctypes.c_void_p:
                return "%r for a pointer to %s" % (py, inner)
            return self.agree(inner, py._type_)
        return "C type %r not understood" % (t,)


class HeaderTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.h = Header(HEADER)
        cls.c = Checker(cls.h)

    def test_header_is_read(self):
        # A parser that found nothing would pass everything below.
        self.assertGreater(len(self.h.functions), 90)
        self.assertGreaterEqual(len(self.h.structs), 15)
        self.assertGreater(len(self.h.constants), 80)
        self.assertIn("nerf_model_load", self.h.functions)
        self.assertEqual(self.h.constants["NERF_MODEL_HAS_BATCH_RECORD"],
                         0x10)

    def test_every_function(self):
        problems = []
        for name, (ret, args) in sorted(self.h.functions.items()):
            proto = _capi._PROTOTYPES.get(name)
            if proto is None:
                problems.append("%s: not in the binding" % name)
                continue
            restype, argtypes, _ = proto
            if len(argtypes) != len(args):
                problems.append("%s: %d arguments in the binding, %d in C"
                                % (name, len(argtypes), len(args)))
                continue
            why = self.c.agree(ret, restype)
            if why:
                problems.append("%s: returns %s" % (name, why))
            for i, (a, p) in enumerate(zip(args, argtypes)):
                why = self.c.agree(a, p)
                if why:
                    problems.append("%s: argument %d: %s" % (name, i + 1, why))
        extra = set(_capi._PROTOTYPES) - set(self.h.functions)
        problems += ["%s: in the binding, not in nerf.h" % n
                     for n in sorted(extra)]
        self.assertEqual(problems, [])

    def test_every_struct(self):
        problems = []
        for name, fields in sorted(self.h.structs.items()):
            mirror = self.c.mirrors.get(name)
            if mirror is None:
                problems.append("%s: no ctypes mirror" % name)
                continue
            py_fields = [(f[0], f[1]) for f in mirror._fields_]
            if [f for f, _ in py_fields] != [f for f, _ in fields]:
                problems.append("%s: fields %s in the binding, %s in C" % (
                    name, [f for f, _ in py_fields], [f for f, _ in fields]))
                continue
            for (field, t), (_, py) in zip(fields, py_fields):
                why = self.c.agree(t, py)
                if why:
                    problems.append("%s.%s: %s" % (name, field, why))
        self.assertEqual(problems, [])

    def test_every_constant(self):
        problems = []
        for name, value in sorted(self.h.constants.items()):
            attr = name[len("NERF_"):]
            if not hasattr(nerf, attr):
                problems.append("%s: no nerf.%s" % (name, attr))
            elif getattr(nerf, attr) != value:
                problems.append("%s: nerf.%s is %r, nerf.h says %r" % (
                    name, attr, getattr(nerf, attr), value))
        self.assertEqual(problems, [])


if __name__ == "__main__":
    HEADER = sys.argv.pop(1)
    unittest.main()
