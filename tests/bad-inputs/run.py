"""The bad-input table: every case in cases.txt, run and checked.

    run.py CASES BINDIR [--only NAME...]

Each line of CASES is one bad input: a program (or a line of Python through
the binding) given something it must refuse, the exit status (or the
exception) it must refuse it with, and a fragment its message must hold.
The runner builds the inputs a case names (the fixtures below), runs the
case with a time limit, so that a reader that blocks fails instead of
hanging the suite, and checks, besides status and message:
  - that no fixture the case was given changed (a program never writes over
    its input, and a refusal leaves every file as it was);
  - the case's own after-conditions (`absent:PATH`, `unchanged:PATH`).

Programs are found in BINDIR (the build's examples/); MESON_EXE_WRAPPER
runs them under an emulator where meson sets one.  Python cases run this
interpreter with the environment meson gives the binding's tests, passed
as NERF_PY_ENV_<NAME> variables (PYTHONPATH, NERF_LIBRARY, an ASan runtime
to preload); without it they are reported as skipped.
NERF_BAD_INPUT_TIMEOUT (seconds, default 60) bounds each case.

Exit status 0 when every case held, 1 otherwise.
"""

import hashlib
import os
import shlex
import shutil
import stat
import subprocess
import sys
import tempfile

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
import fixtures  # noqa: E402 (after the line above)

# Each program and where the build puts it under BINDIR.  nerf-viewer is
# built only where SDL2 is found, nerf-frames only where FFmpeg's
# libraries are: without them their cases are skipped.
PROGRAMS = {"nerf-scene": "nerf-scene", "nerf-train": "nerf-train",
            "nerf-render": "nerf-render", "nerf-eval": "nerf-eval",
            "nerf-info": "nerf-info", "nerf-export": "nerf-export",
            "nerf-viewer": os.path.join("viewer", "nerf-viewer"),
            "nerf-frames": "nerf-frames"}
OPTIONAL = ("nerf-viewer", "nerf-frames")


class Skip(Exception):
    """The case cannot run in this build; the text says why."""


class Case:
    def __init__(self, where, name, expect, message, command, after):
        self.where = where      # "cases.txt:LINE", for messages
        self.name = name
        self.expect = expect    # exit status (str of an int) or exception
        self.message = message
        self.command = command
        self.after = after      # ["absent:PATH", "unchanged:PATH", ...]

    @property
    def is_python(self):
        return self.command.startswith("python:")


def parse(path):
    """The cases of the table: NAME | EXPECT | MESSAGE | COMMAND [| AFTER]."""
    cases, names = [], set()
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            text = line.strip()
            if not text or text.startswith("#"):
                continue
            where = "%s:%d" % (os.path.basename(path), number)
            cells = [c.strip() for c in text.split(" | ")]
            if len(cells) not in (4, 5) or not all(cells[:4]):
                sys.exit("%s: expected NAME | EXPECT | MESSAGE | COMMAND "
                         "[| AFTER], got %d cells" % (where, len(cells)))
            name = cells[0]
            if name in names:
                sys.exit("%s: case %s is in the table twice" % (where, name))
            names.add(name)
            after = cells[4].split() if len(cells) == 5 else []
            cases.append(Case(where, name, cells[1], cells[2], cells[3],
                              after))
    return cases


def digest(path):
    """A fingerprint of what is at path: its kind, and the bytes of every
    regular file under it (FIFOs and devices are never opened)."""
    h = hashlib.sha256()
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return "absent"
    h.update(b"%o" % stat.S_IFMT(st.st_mode))
    if stat.S_ISDIR(st.st_mode):
        for entry in sorted(os.listdir(path)):
            h.update(entry.encode() + b"\0")
            h.update(digest(os.path.join(path, entry)).encode())
    elif stat.S_ISREG(st.st_mode):
        with open(path, "rb") as f:
            h.update(f.read())
    return h.hexdigest()


class Runner:
    def __init__(self, bindir, work):
        self.bindir = bindir
        self.work = work
        self.wrap = shlex.split(os.environ.get("MESON_EXE_WRAPPER", ""))
        self.timeout = float(os.environ.get("NERF_BAD_INPUT_TIMEOUT", "60"))
        self.fixtures = fixtures.Fixtures(self, os.path.join(work, "fixtures"))

    def program(self, name):
        path = os.path.join(self.bindir, PROGRAMS.get(name, name))
        if name in OPTIONAL and not os.path.exists(path):
            raise Skip("%s is not built" % name)
        return self.wrap + [path]

    def run(self, argv, env=None):
        """Run argv with the case time limit; (status, stdout, stderr), or
        status None when it did not finish in time."""
        try:
            p = subprocess.run(argv, stdin=subprocess.DEVNULL,
                               capture_output=True, timeout=self.timeout,
                               env=env)
        except subprocess.TimeoutExpired as e:
            return None, e.stdout or b"", e.stderr or b""
        return p.returncode, p.stdout, p.stderr

    def substitute(self, case, text, tmp, quote):
        """Replace each {fixture} (and {tmp}) in text by its path; the
        fixtures used are returned so that they can be checked after."""
        used = {}
        out, i = [], 0
        while i < len(text):
            j = text.find("{", i)
            if j < 0:
                out.append(text[i:])
                break
            k = text.find("}", j)
            if k < 0:
                raise ValueError("%s: unclosed '{'" % case.where)
            out.append(text[i:j])
            key = text[j + 1:k]
            if key == "tmp":
                path = tmp
            else:
                path = self.fixtures.get(key)
                used[key] = path
            out.append(quote(path))
            i = k + 1
        return "".join(out), used

    def check(self, case):
        """Run one case; None when it held, else what went wrong."""
        tmp = tempfile.mkdtemp(prefix=case.name + ".", dir=self.work)
        if case.is_python:
            source, used = self.substitute(
                case, case.command[len("python:"):].strip(), tmp, repr)
            argv = [sys.executable, "-c", PY_DRIVER, source]
            env = dict(os.environ)
            env.update(python_env())
        else:
            env = None
            command, used = self.substitute(case, case.command, tmp,
                                            shlex.quote)
            argv = shlex.split(command)
            if argv[0] not in PROGRAMS:
                return "%s: unknown program %s" % (case.where, argv[0])
            argv = self.program(argv[0]) + argv[1:]
        after, more = self.substitute(case, " ".join(case.after), tmp, str)
        used.update(more)
        before = {key: digest(path) for key, path in used.items()}
        marks = {}
        for cond in after.split():
            kind, _, path = cond.partition(":")
            if kind == "unchanged":
                marks[path] = digest(path)
            elif kind != "absent":
                return "%s: unknown after-condition %s" % (case.where, cond)

        status, out, err = self.run(argv, env)
        err = err.decode("utf-8", "replace")
        problems = []
        if status is None:
            problems.append("did not finish in %g s (blocked?)"
                            % self.timeout)
        elif case.is_python:
            got = err.strip().splitlines()[-1] if err.strip() else ""
            name = got.split(":", 1)[0]
            if status == 0:
                problems.append("raised nothing, expected " + case.expect)
            elif status != 3:
                problems.append("python exited with status %d" % status)
            elif name != case.expect:
                problems.append("raised %s, expected %s" % (got, case.expect))
        elif status != int(case.expect):
            problems.append("status %d, expected %s" % (status, case.expect))
        if status is not None and case.message not in err:
            problems.append("message lacks '%s'" % case.message)
        for key, path in used.items():
            if digest(path) != before[key]:
                problems.append("changed its input {%s} (%s)" % (key, path))
        for cond in after.split():
            kind, _, path = cond.partition(":")
            if kind == "absent" and os.path.lexists(path):
                problems.append("left %s behind" % path)
            if kind == "unchanged" and digest(path) != marks[path]:
                problems.append("changed %s" % path)
        if problems:
            return "%s\n  %s\n  stderr: %s" % (
                "; ".join(problems), " ".join(shlex.quote(a) for a in argv),
                err.strip().replace("\n", "\n          ") or "(empty)")
        shutil.rmtree(tmp, ignore_errors=True)
        return None


PY_PREFIX = "NERF_PY_ENV_"


def python_env():
    """The binding's environment, from the variables meson passes."""
    return {k[len(PY_PREFIX):]: v for k, v in os.environ.items()
            if k.startswith(PY_PREFIX)}


# A Python case runs this with its line as argv[1]: the last line of
# stderr names the exception; status 3 means one was raised.
PY_DRIVER = r"""
import sys
import nerf
try:
    exec(sys.argv[1])
except Exception as e:
    sys.stderr.write("%s: %s\n" % (type(e).__name__, e))
    sys.exit(3)
"""


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    cases = parse(argv[1])
    if len(argv) > 3 and argv[3] == "--only":
        cases = [c for c in cases if c.name in argv[4:]]
    skip_python = None
    py = python_env()
    if "NERF_LIBRARY" not in py:
        skip_python = "no NERF_LIBRARY: the binding's environment is not set"
    elif py.get("NERF_PY_SKIP"):
        skip_python = py["NERF_PY_SKIP"]
    work = tempfile.mkdtemp(prefix="nerf-bad-inputs.")
    failed = skipped = 0
    try:
        runner = Runner(argv[2], work)
        for case in cases:
            if case.is_python and skip_python:
                print("skip %s (%s)" % (case.name, skip_python))
                skipped += 1
                continue
            try:
                problem = runner.check(case)
            except fixtures.FixtureError as e:
                problem = "fixture: %s" % e
            except Skip as e:
                print("skip %s (%s)" % (case.name, e))
                skipped += 1
                continue
            if problem:
                failed += 1
                print("FAIL %s (%s): %s" % (case.name, case.where, problem))
            else:
                print("ok   %s" % case.name)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print("%d cases: %d held, %d failed, %d skipped"
          % (len(cases), len(cases) - failed - skipped, failed, skipped))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
