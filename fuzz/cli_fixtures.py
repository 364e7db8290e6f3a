"""fuzz_cli.py's fixtures: the small inputs every run finds in its scratch folder, made once per
campaign with the vtex under test, and the snapshot that tells what a run changed."""

import ctypes
import hashlib
import json
import os
import shutil
import stat
import struct
import subprocess
import sys

# ---------------------------------------------------------------------------------------------
# Fixtures: small inputs every run finds in its scratch folder (made once per campaign).

HILL_OBJ = "".join(
    f"v {-1 + 0.5 * i} {-1 + 0.5 * j} {0.2 * ((i + j) % 2)}\n" for j in range(5) for i in range(5)
) + "".join(
    f"f {j * 5 + i + 1} {j * 5 + i + 2} {j * 5 + i + 7} {j * 5 + i + 6}\n" for j in range(4) for i in range(4)
)
HUGE_OBJ = "v -1e19 -1e19 0\nv 1e19 -1e19 0\nv 1e19 1e19 0\nv -1e19 1e19 0\nf 1 2 3 4\n"
CROSS_OBJ = ("v 0.1 0.5 0.1\nv 0.9 0.5 0.1\nv 0.9 0.5 0.9\nv 0.1 0.5 0.9\n"
             "v 0.5 0.1 0.1\nv 0.5 0.9 0.1\nv 0.5 0.9 0.9\nv 0.5 0.1 0.9\nf 1 2 3 4\nf 5 6 7 8\n")


def scene_text(camera="[0.0, -3.0, 2.0]", size=(32, 24), color="[3.0, 3.0, 3.0]", specular="[0.04, 0.04, 0.04]",
               mesh="hill.obj", volume="bush.vto", source="bush.glb"):
    return f"""[camera]
position = {camera}
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0
width = {size[0]}
height = {size[1]}

[[light]]
type = "directional"
direction = [-1.0, 0.5, -1.0]
color = {color}

[[texel]]
name = "cover"
volume = "{volume}"
source = "{source}"
material = {{ diffuse = [1.0, 1.0, 1.0], specular = {specular}, shininess = 20.0 }}

[[surface]]
mesh = "{mesh}"
texel = "cover"
height = 0.25
"""


PIPELINE = """[pipeline]
output = "pipeline-out"

[[source]]
name = "bush"
file = "bush.glb"

[[source]]
name = "grass"
pattern = "grass"
count = 4

[[texel]]
name = "bush"
source = "bush"
resolution = 8

[[texel]]
name = "grass"
source = "grass"
resolution = 8

[[render]]
name = "a"
scene = "scene.toml"
texels = { cover = "bush" }
width = 16
height = 12

[[render]]
name = "b"
scene = "scene.toml"
texels = { cover = "grass" }
width = 16
height = 12
"""
COMPARE_C = '\n[[compare]]\nname = "c"\na = "a"\nb = "b"\n'
COMPARE_C_MANIFEST = '\n[[compare]]\nname = "c.manifest"\na = "a"\nb = "b"\n'


def xxh3():
    try:
        lib = ctypes.CDLL("libxxhash.so.0")
    except OSError:
        return None
    lib.XXH3_64bits.restype = ctypes.c_uint64
    lib.XXH3_64bits.argtypes = [ctypes.c_char_p, ctypes.c_size_t]
    return lambda b: lib.XXH3_64bits(b, len(b))


def read_container(data):
    count = struct.unpack_from("<I", data, 12)[0]
    sections = []
    for s in range(count):
        tag, _, offset, size, _ = struct.unpack_from("<4sIQQQ", data, 24 + 32 * s)
        sections.append([tag, data[offset:offset + size]])
    return data[:8], struct.unpack_from("<I", data, 8)[0], sections


def write_container(magic, version, sections, h):
    table = b""
    offset = 24 + 32 * len(sections)
    for tag, payload in sections:
        table += struct.pack("<4sIQQQ", tag, 0, offset, len(payload), h(payload))
        offset += len(payload)
    head = magic + struct.pack("<II", version, len(sections))
    guard = h(head + table)
    return head + struct.pack("<Q", guard) + table + b"".join(p for _, p in sections)


def bad_vtls(good):
    """The .vtl cases of issue 14: checksummed files with wrong content (docs/formats.md)."""
    h = xxh3()
    if h is None:
        return {}
    magic, version, sections = read_container(good)
    voxl = [i for i, (tag, _) in enumerate(sections) if tag == b"VOXL"][0]

    def with_voxel(offset, fmt, *values):
        s = [list(x) for x in sections]
        payload = bytearray(s[voxl][1])
        struct.pack_into(fmt, payload, 8 + 10 + offset, *values)  # first block's voxel record
        s[voxl][1] = bytes(payload)
        return write_container(magic, version, s, h)

    head = [s for s in sections if s[0] == b"HEAD"][0]
    return {
        "zero-quaternion.vtl": with_voxel(4, "<4f", 0, 0, 0, 0),
        "zero-sigma.vtl": with_voxel(20, "<3f", 0, 0, 0),
        "negative-albedo.vtl": with_voxel(32, "<3f", -1, 0.5, 0.5),
        "huge-albedo.vtl": with_voxel(32, "<3f", 3e38, 3e38, 3e38),
        "duplicate-head.vtl": write_container(magic, version, [head] + sections, h),
        "unknown-section.vtl": write_container(magic, version, sections + [[b"XTRA", b"hello"]], h),
    }


def make_fixtures(vtex, folder, env):
    """Builds the pristine fixture folder with the vtex under test; returns its description."""
    if os.path.exists(folder):
        shutil.rmtree(folder)
    os.makedirs(folder)

    def write(name, text):
        with open(os.path.join(folder, name), "w" if isinstance(text, str) else "wb") as f:
            f.write(text)

    def run(*args):
        r = subprocess.run([vtex, "-q", *args], cwd=folder, env=env, capture_output=True, text=True, timeout=600)
        if r.returncode != 0:
            sys.exit(f"fixture command failed: vtex {' '.join(args)}\n{r.stderr}")

    write("hill.obj", HILL_OBJ)
    write("cross.obj", CROSS_OBJ)
    write("huge.obj", HUGE_OBJ)
    run("pattern", "bush", "-o", "bush.glb", "--leaves", "30")
    run("pattern", "grass", "-o", "grass.glb", "--count", "4")
    run("sample", "bush.glb", "-o", "bush.vtl", "--resolution", "8")
    run("build", "bush.vtl", "-o", "bush.vto")
    write("scene.toml", scene_text())
    write("plain.toml", scene_text().split("[[texel]]")[0] + '[[surface]]\nmesh = "hill.obj"\n')
    write("far-camera.toml", scene_text(camera="[0.0, -2e18, 0.5]"))
    write("huge-mesh.toml", scene_text(mesh="huge.obj"))
    write("bright.toml", scene_text(color="[1e308, 1e308, 1e308]"))
    write("shiny.toml", scene_text(specular="[1e300, 1e300, 1e300]"))
    write("nul-path.toml", scene_text(mesh="hill\\u0000.obj"))
    write("big.toml", scene_text(size=(16384, 16384)))
    run("render", "scene.toml", "-o", "a.exr", "--width", "16", "--height", "12")
    run("reference", "scene.toml", "-o", "b.exr", "--width", "16", "--height", "12", "--spp", "1")
    run("render", "scene.toml", "-o", "small.exr", "--width", "8", "--height", "6")
    write("pipeline.toml", PIPELINE + COMPARE_C)
    write("collide.toml", PIPELINE + COMPARE_C + COMPARE_C_MANIFEST)
    with open(os.path.join(folder, "bush.vtl"), "rb") as f:
        for name, data in bad_vtls(f.read()).items():
            write(name, data)
    os.makedirs(os.path.join(folder, "dir"))
    os.makedirs(os.path.join(folder, "dir.toml"))
    # Special files are made again in every run folder (copying a FIFO would block).
    specials = {"fifo": "fifo", "fifo.toml": "fifo", "fifo.exr": "fifo", "zero.toml": "/dev/zero",
                "zero.vtl": "/dev/zero", "full.exr": "/dev/full", "loop-a": "loop-b", "loop-b": "loop-a",
                "link.toml": "scene.toml"}
    with open(os.path.join(folder, "specials.json"), "w") as f:
        json.dump(specials, f)
    return specials


def populate(pristine, run_dir, specials):
    if os.path.lexists(run_dir):
        shutil.rmtree(run_dir)
    shutil.copytree(pristine, run_dir, symlinks=True, ignore=lambda d, names: ["specials.json"])
    for name, what in specials.items():
        path = os.path.join(run_dir, name)
        if what == "fifo":
            os.mkfifo(path)
        else:
            os.symlink(what, path)


def snapshot(folder):
    """Every entry under `folder`: (type, inode, size, content hash) for regular files."""
    entries = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            path = os.path.join(root, name)
            rel = os.path.relpath(path, folder)
            st = os.lstat(path)
            if stat.S_ISREG(st.st_mode):
                with open(path, "rb") as f:
                    digest = hashlib.sha1(f.read()).hexdigest()
                entries[rel] = ("file", st.st_ino, st.st_size, digest)
            elif stat.S_ISLNK(st.st_mode):
                entries[rel] = ("link", os.readlink(path))
            elif stat.S_ISDIR(st.st_mode):
                entries[rel] = ("dir",)
            else:
                entries[rel] = ("special", stat.S_IFMT(st.st_mode))
    return entries
