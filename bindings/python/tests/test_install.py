"""The installed tree, used the way users use it.

Usage (from meson.build):

    test_install.py --build BUILD --meson MESON --prefix PREFIX
        --libdir LIBDIR --package-dir DIR --version VERSION
        --sanitize B_SANITIZE --source-package bindings/python/nerf
        --cc CC...

The build is installed with ``meson install --destdir`` into a scratch
folder (BUILD/py-install/stage); then

- the Python package is imported by a fresh /usr/bin/python3 that sees
  nothing but the stage: no site module (-S, so no system or user
  site-packages), PYTHONPATH the staged site-packages only, the current
  directory a scratch folder and kept off sys.path, and no NERF_LIBRARY
  or LD_LIBRARY_PATH.  It must load the staged libnerf (which it finds
  through the generated _config.py, by its place relative to the
  package) and render a few pixels;
- a C program is compiled and linked with the flags of the staged
  pkg-config file, with an rpath to the staged library directory (no
  LD_LIBRARY_PATH), and must render with the staged libnerf.

--destdir rather than a separate build with a scratch prefix: that would
cost a second build of the library (27 s with -j1, tests and examples off,
on a busy 2-core machine, against about 2 s for this whole test), and the
installed package finds its library by its relative place first, which is
what a staged tree exercises.  The absolute path in _config.py, the
fallback, is checked for the configured value.

Exit status 77 (skipped) without meson, pkg-config or a C compiler, or
when NERF_PY_SKIP says why the Python side cannot run here.
"""

import argparse
import ast
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

# A few pixels through the public API, printing what was loaded from where.
PY_CHECK = r"""
import math, sys
import nerf
from nerf import _loader
print("nerf", nerf.__file__)
print("library", nerf.library_path())
print("config", _loader._config.LIBDIR, _loader._config.PACKAGE_DIR)
print("version", nerf.version_string())
print("sys.path", sys.path)
model = nerf.Model(preset="tiny", seed=1)
sampler = nerf.Sampler(preset="tiny")
renderer = nerf.Renderer(model, sampler, threads=1)
cam = nerf.Camera.from_fov(4, 3, 40.0, eye=(3.0, -3.0, 2.0))
out = renderer.render_image(cam)
rgb = [v for row in out.rgb.tolist() for px in row for v in px]
opacity = [v for row in out.opacity.tolist() for v in row]
assert len(rgb) == 36 and len(opacity) == 12, (len(rgb), len(opacity))
assert all(math.isfinite(v) for v in rgb), rgb
assert all(0.0 <= v <= 1.0 + 1e-6 for v in opacity), opacity
assert max(opacity) > 0.0, opacity
print("rendered", sum(opacity))
"""

C_CHECK = r"""
#include <nerf.h>
#include <stdio.h>
#include <string.h>

/* The libnerf this process mapped, from /proc/self/maps. */
static void print_library(void)
{
    FILE *f = fopen("/proc/self/maps", "r");
    char line[4096];
    while (f != NULL && fgets(line, sizeof line, f) != NULL) {
        char *path = strchr(line, '/');
        if (path != NULL && strstr(path, "/libnerf.so") != NULL) {
            printf("library %s", path);
            break;
        }
    }
    if (f != NULL) {
        fclose(f);
    }
}

int main(void)
{
    nerf_model_options mo;
    nerf_sampler_options so;
    nerf_camera cam;
    nerf_model *m = NULL;
    nerf_sampler *s = NULL;
    nerf_renderer *r = NULL;
    float opacity[12];
    const float eye[3] = {3.0f, -3.0f, 2.0f}, at[3] = {0, 0, 0},
                up[3] = {0, 0, 1};
    int rc;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_TINY);
    NERF_SAMPLER_OPTIONS_INIT(&so);
    nerf_sampler_options_preset(&so, NERF_PRESET_TINY);
    NERF_CAMERA_INIT(&cam);
    cam.width = 4;
    cam.height = 3;
    cam.fx = cam.fy = 5.0f;
    cam.cx = 2.0f;
    cam.cy = 1.5f;
    nerf_camera_look_at(&cam, eye, at, up);
    rc = nerf_model_create(&m, &mo);
    if (rc == NERF_OK) {
        rc = nerf_sampler_create(&s, &so);
    }
    if (rc == NERF_OK) {
        rc = nerf_renderer_create(&r, m, s, NULL);
    }
    if (rc == NERF_OK) {
        rc = nerf_renderer_render_image(r, &cam, NULL, NULL, opacity, 12);
    }
    if (rc != NERF_OK) {
        printf("failed: %s\n", nerf_last_error());
    } else {
        double sum = 0;
        int i;
        for (i = 0; i < 12; i++) {
            sum += opacity[i];
        }
        printf("version %s\nrendered %g\n", nerf_version_string(), sum);
        print_library();
    }
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
    return rc != NERF_OK;
}
"""

SKIP = 77


class Failed(Exception):
    pass


def run(cmd, **kw):
    """Run cmd; return its output, or raise Failed showing all of it."""
    out = subprocess.run(cmd, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, timeout=300,
                         **kw)
    if out.returncode != 0:
        raise Failed("%s exited with %d:\n%s"
                     % (" ".join(map(str, cmd)), out.returncode, out.stdout))
    return out.stdout


def field(text, key):
    m = re.search(r"^%s (.*)$" % re.escape(key), text, re.M)
    if not m:
        raise Failed("no '%s' line in:\n%s" % (key, text))
    return m.group(1).strip()


def inside(path, folder):
    path, folder = os.path.realpath(path), os.path.realpath(folder)
    return path == folder or path.startswith(folder + os.sep)


def staged(stage, path):
    """Where an absolute install path lands under --destdir stage."""
    return stage / Path(path).relative_to(Path(path).anchor)


def clean_env():
    """The environment of the checked programs: nothing that points at the
    build or source tree, nor the library search path.  A sanitizer build's
    runtime preload (LD_PRELOAD, ASAN_OPTIONS, PYTHONMALLOC) is kept."""
    drop = {"PYTHONPATH", "NERF_LIBRARY", "LD_LIBRARY_PATH", "PYTHONHOME",
            "PYTHONSTARTUP", "PYTHONUSERBASE", "PKG_CONFIG_PATH"}
    return {k: v for k, v in os.environ.items() if k not in drop}


def install(args, stage):
    cmd = [args.meson, "install", "-C", args.build, "--destdir", str(stage)]
    # meson test builds only what the tests it runs need: a fresh build may
    # lack programs install wants.  Only then let install build them (the
    # test is not parallel, so nothing runs under that build).
    try:
        run(cmd + ["--no-rebuild"])
    except Failed:
        print("install --no-rebuild failed; installing with a rebuild")
        run(cmd)


def check_files(args, stage):
    pkg = staged(stage, args.package_dir)
    want = sorted(p.name for p in Path(args.source_package).glob("*.py"))
    got = sorted(p.name for p in pkg.glob("*.py") if p.name != "_config.py")
    if want != got:
        raise Failed("installed package %s holds %s; the source has %s"
                     % (pkg, got, want))
    config = (pkg / "_config.py").read_text()
    for name, value in (("LIBDIR", args.libdir),
                        ("PACKAGE_DIR", args.package_dir),
                        ("VERSION", args.version)):
        if '%s = "%s"' % (name, value) not in config:
            raise Failed("_config.py lacks %s = \"%s\":\n%s"
                         % (name, value, config))
    print("ok   %d modules and _config.py installed in %s"
          % (len(got), args.package_dir))


def check_python(args, scratch, stage):
    site = staged(stage, args.package_dir).parent
    env = clean_env()
    env.update(PYTHONPATH=str(site), PYTHONSAFEPATH="1",
               PYTHONNOUSERSITE="1", PYTHONDONTWRITEBYTECODE="1")
    out = run(["/usr/bin/python3", "-S", "-s", "-c", PY_CHECK], env=env,
              cwd=str(scratch))
    if not inside(field(out, "nerf"), site):
        raise Failed("nerf imported from outside the stage:\n" + out)
    library = field(out, "library")
    if not inside(library, staged(stage, args.libdir)):
        raise Failed("libnerf loaded from outside the staged libdir %s:\n%s"
                     % (staged(stage, args.libdir), out))
    if field(out, "version") != args.version:
        raise Failed("version %s, expected %s" % (field(out, "version"),
                                                   args.version))
    for entry in ast.literal_eval(field(out, "sys.path")):
        for tree in (args.build, str(Path(args.source_package).parents[2])):
            if entry and inside(entry, tree) and not inside(entry, stage):
                raise Failed("sys.path reaches %s: %s" % (tree, entry))
    print("ok   python3 -S with only the stage on its path imports nerf, "
          "loads %s and renders" % library)


def check_c(args, scratch, stage):
    pcs = list(stage.rglob("pkgconfig/nerf.pc"))
    if not pcs:
        raise Failed("no pkgconfig/nerf.pc under %s" % stage)
    # The .pc names the configured prefix, where nothing was installed:
    # point its absolute variables into the stage (as tests/abi/pkgconfig.sh
    # does; PKG_CONFIG_SYSROOT_DIR would move the system paths of the
    # libraries it requires too).
    original = pcs[0].read_text()
    if "prefix=%s\n" % args.prefix not in original:
        raise Failed("%s does not name the prefix %s:\n%s"
                     % (pcs[0], args.prefix, original))
    pcdir = scratch / "pc"
    pcdir.mkdir()
    text = re.sub(r"^([A-Za-z_][A-Za-z0-9_]*)=/",
                  lambda m: "%s=%s/" % (m.group(1), stage),
                  original, flags=re.M)
    (pcdir / "nerf.pc").write_text(text)
    env = clean_env()
    env["PKG_CONFIG_PATH"] = str(pcdir)
    flags = run(["pkg-config", "--cflags", "--libs", "nerf"], env=env).split()
    libdir = run(["pkg-config", "--variable=libdir", "nerf"], env=env).strip()
    if libdir != str(staged(stage, args.libdir)):
        raise Failed("pkg-config libdir %s, expected the staged %s"
                     % (libdir, staged(stage, args.libdir)))
    src = scratch / "render.c"
    src.write_text(C_CHECK)
    exe = scratch / "render"
    san = ([] if args.sanitize in ("", "none")
           else ["-fsanitize=" + args.sanitize])
    cflags = [f for f in flags if not f.startswith(("-l", "-L"))]
    libs = [f for f in flags if f.startswith(("-l", "-L"))]
    run(args.cc + ["-std=c11", "-Wall", "-Wextra", "-Werror"] + san + cflags
        + [str(src), "-o", str(exe)] + libs + ["-Wl,-rpath," + libdir],
        env=env)
    env.pop("PKG_CONFIG_PATH")
    out = run([str(exe)], env=env)
    if field(out, "version") != args.version:
        raise Failed("the C program printed:\n" + out)
    if not inside(field(out, "library"), libdir):
        raise Failed("the C program loaded libnerf from outside %s:\n%s"
                     % (libdir, out))
    print("ok   C program built with pkg-config (rpath %s) renders with %s"
          % (libdir, field(out, "library")))


def main():
    p = argparse.ArgumentParser()
    for name in ("build", "meson", "prefix", "libdir", "package-dir",
                 "version", "sanitize", "source-package"):
        p.add_argument("--" + name, required=True)
    p.add_argument("--cc", nargs="+", required=True,
                   help="the C compiler command (last)")
    args = p.parse_args()
    for tool in (args.meson, "pkg-config", args.cc[0]):
        if shutil.which(tool) is None:
            print("%s not found: skipping" % tool)
            return SKIP
    skip_python = os.environ.get("NERF_PY_SKIP")
    scratch = Path(args.build) / "py-install"
    stage = scratch / "stage"
    shutil.rmtree(scratch, ignore_errors=True)
    stage.mkdir(parents=True)
    try:
        install(args, stage)
        check_files(args, stage)
        if skip_python:
            print("python side skipped: " + skip_python)
        else:
            check_python(args, scratch, stage)
        check_c(args, scratch, stage)
    except Failed as err:
        print("FAIL " + str(err))
        return 1
    return SKIP if skip_python else 0


if __name__ == "__main__":
    sys.exit(main())
