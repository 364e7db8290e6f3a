"""fuzz_cli.py's mutations of a command line, and what an argv names: its outputs and the
files it reads (directly, or through a scene or a pipeline among the fixtures)."""

import os
import re

# ---------------------------------------------------------------------------------------------
# Mutation.

COMMANDS = ["ingest", "pattern", "sample", "build", "inspect", "render", "reference", "compare", "run", "demo",
            "help"]
FLAGS = {
    "": ["-q", "--quiet", "-v", "--verbose", "--help", "--version", "-h"],
    "ingest": ["-o", "--output", "--report", "--max-triangles", "--weld-tolerance", "--drop-invalid", "--up", "--fit"],
    "pattern": ["-o", "--output", "--seed", "--count", "--leaves", "--fluctuation", "--lean", "--variant"],
    "sample": ["-o", "--output", "-r", "--resolution", "--cyclic", "--solid", "--solid-density", "--bounds",
               "--max-memory", "--threads"],
    "build": ["-o", "--output", "--filter", "--tolerance", "--filter-error-samples", "--max-memory", "--source",
              "--threads"],
    "inspect": ["--json", "--source"],
    "render": ["-o", "--output", "--png", "--width", "--height", "--stats", "--threads", "--aov", "--max-memory",
               "--spp", "--lod-bias", "--shadow-refresh", "--exact", "--hybrid", "--shading", "--level-fit"],
    "reference": ["-o", "--output", "--png", "--width", "--height", "--stats", "--threads", "--aov", "--spp",
                  "--mode", "--tolerance", "--max-memory"],
    "compare": ["--json", "--diff"],
    "run": ["-o", "--output", "--force", "--jobs", "--max-memory", "--wait", "--threads"],
    "demo": ["-o", "--output", "--resolution", "--scale", "--seed", "--force", "--jobs", "--threads"],
}
ALL_FLAGS = sorted({f for fl in FLAGS.values() for f in fl})
WORDS = ["grass", "bush", "fur", "brushed", "blocks", "neyret", "sggx", "auto", "on", "off", "unit", "fit", "cell",
         "keep", "fast", "reference", "embedded", "deformed", "concentric", "radial", "4GiB", "512MB", "1KB", "0B", "-",
         "--", "=", "true", "x"]
NUMBERS = ["nan", "NaN", "-nan", "inf", "-inf", "infinity", "-0", "0", "-0.0", "1e308", "-1e308", "1e-308", "4.9e-324",
           "1e309", "1", "2", "3", "4", "7", "8", "16", "64", "128", "1024", "4096", "16384", "16385", "65536",
           "1048576", "2097152", "2147483647", "2147483648", "4294967296", "9223372036854775807",
           "18446744073709551616", "-1", "-2147483649", "", " ", "0x10", "1e3", "1.5", ".5", "5.", "+1", "1 ",
           "١", "0.001", "0.0009", "1e6", "1e12", "32", "-32", "33", "1e-6", "1024.0"]
FIXTURE_PATHS = ["hill.obj", "cross.obj", "huge.obj", "bush.glb", "grass.glb", "bush.vtl", "bush.vto", "scene.toml",
                 "plain.toml", "far-camera.toml", "huge-mesh.toml", "bright.toml", "shiny.toml", "nul-path.toml",
                 "big.toml", "a.exr", "b.exr", "small.exr", "pipeline.toml", "collide.toml", "zero-quaternion.vtl",
                 "zero-sigma.vtl", "negative-albedo.vtl", "huge-albedo.vtl", "duplicate-head.vtl",
                 "unknown-section.vtl"]
SPECIAL_PATHS = ["fifo", "fifo.toml", "fifo.exr", "zero.toml", "zero.vtl", "full.exr", "/dev/full", "/dev/null",
                 "/dev/zero", "dir", "dir.toml", "dir/", ".", "..", "/", "missing.toml", "missing/x.exr", "loop-a",
                 "link.toml", "a" * 300 + ".exr", "x/" * 600 + "y.exr", "caf\u00e9.exr", "new\nline.exr",
                 "tab\t.exr", "\x01ctrl.exr", "-o", "out.exr", "out.png", "out.json", "out.vtl", "out.vto",
                 "out.glb", "outdir", "sub/new.exr"]
STRUCTURED = [0.0]  # the share of structured mutations (--structured)
PATH_LIKE = re.compile(r"\.(obj|glb|gltf|vtl|vto|toml|exr|png|json|ply|off|stl)$|^/|/")


def is_number(token):
    try:
        float(token)
        return True
    except ValueError:
        return False


def command_of(argv):
    for t in argv:
        if t in COMMANDS:
            return t
    return ""


def random_token(rng, argv):
    pick = rng.random()
    if pick < 0.25:
        return rng.choice(FLAGS.get(command_of(argv), []) + FLAGS[""])
    if pick < 0.35:
        return rng.choice(ALL_FLAGS)
    if pick < 0.5:
        return rng.choice(NUMBERS)
    if pick < 0.65:
        return rng.choice(FIXTURE_PATHS)
    if pick < 0.8:
        return rng.choice(SPECIAL_PATHS)
    if pick < 0.9:
        return rng.choice(WORDS)
    if pick < 0.95:
        return rng.choice(COMMANDS)
    return rng.choice(argv) if argv else "x"


def mutate_token(rng, token, argv):
    if is_number(token) or token in NUMBERS:
        return rng.choice(NUMBERS)
    if PATH_LIKE.search(token) or token in FIXTURE_PATHS or token in SPECIAL_PATHS:
        r = rng.random()
        if r < 0.4:
            return rng.choice(SPECIAL_PATHS)
        if r < 0.7:
            return rng.choice(FIXTURE_PATHS)
        inputs = [t for t in argv if t in FIXTURE_PATHS]
        if inputs and r < 0.85:
            return rng.choice(inputs)  # the command's own input as another argument
        return token + rng.choice([".tmp.x", "/", "~", ".exr", "/x"])
    if token.startswith("-"):
        r = rng.random()
        if r < 0.5:
            return rng.choice(ALL_FLAGS)
        if r < 0.8:
            return token + "=" + rng.choice(NUMBERS + FIXTURE_PATHS + WORDS)
        return token.upper() if r < 0.9 else "-" + token
    return random_token(rng, argv)


# What each command's options take, for the structured mutations: "out" an output path, "dir"
# an output folder, "in" an input path, "num" a number, "size" a byte size, a list a choice,
# None a flag.
CHOICES = {"pattern": ["grass", "bush", "fur", "brushed", "blocks"], "solid": ["auto", "on", "off"],
           "bounds": ["auto", "unit", "fit"], "filter": ["neyret", "sggx"], "hybrid": ["on", "off"],
           "shading": ["fast", "reference"], "mode": ["embedded", "deformed"], "variant": ["concentric", "radial"],
           "up": ["x", "y", "z"], "fit": ["keep", "cell"], "level-fit": ["on", "off"]}
IMAGE = {"-o": "out", "--png": "out", "--stats": "out", "--width": "num", "--height": "num", "--threads": "num",
         "--max-memory": "size",
         "--aov": None}
OPTIONS = {
    "ingest": {"-o": "out", "--report": "out", "--max-triangles": "num", "--weld-tolerance": "num",
               "--drop-invalid": None, "--up": CHOICES["up"], "--fit": CHOICES["fit"]},
    "pattern": {"-o": "out", "--seed": "num", "--count": "num", "--leaves": "num", "--fluctuation": "num",
                "--lean": "num", "--variant": CHOICES["variant"]},
    "sample": {"-o": "out", "-r": "num", "--cyclic": None, "--solid": CHOICES["solid"], "--solid-density": "num",
               "--bounds": CHOICES["bounds"], "--max-memory": "size", "--threads": "num"},
    "build": {"-o": "out", "--filter": CHOICES["filter"], "--tolerance": "num", "--filter-error-samples": "num",
              "--max-memory": "size", "--source": "in", "--threads": "num"},
    "inspect": {"--json": None, "--source": "in"},
    "render": dict(IMAGE, **{"--spp": "num", "--lod-bias": "num", "--shadow-refresh": "num", "--exact": None,
                             "--hybrid": CHOICES["hybrid"], "--shading": CHOICES["shading"],
                             "--level-fit": CHOICES["level-fit"]}),
    "reference": dict(IMAGE, **{"--spp": "num", "--mode": CHOICES["mode"], "--tolerance": "num"}),
    "compare": {"--json": None, "--diff": "out"},
    "run": {"-o": "dir", "--force": None, "--jobs": "num", "--max-memory": "size", "--wait": None, "--threads": "num"},
    "demo": {"-o": "dir", "--resolution": "num", "--scale": "num", "--seed": "num", "--force": None, "--jobs": "num",
             "--threads": "num"},
}
SMALL = ["0", "1", "2", "4", "8", "16", "0.5", "0.01", "-1", "1e-6"]
SIZES = ["0", "1", "1KB", "64MB", "512MB", "4GiB", "1e3", "-1", "nan", "", "1TB", "18446744073709551616"]
OUTPUT_TARGETS = ["out.exr", "out.png", "out.json", "out.glb", "out.vtl", "out.vto", "sub/out.exr", "outdir"]


def value_for(rng, kind, argv):
    if kind == "num":
        return rng.choice(SMALL if rng.random() < 0.5 else NUMBERS)
    if kind == "size":
        return rng.choice(SIZES)
    if isinstance(kind, list):
        return rng.choice(kind + ["", "x", kind[0].upper()]) if rng.random() < 0.2 else rng.choice(kind)
    if kind in ("out", "dir"):
        r = rng.random()
        read = sorted(t for t in inputs_named(argv) if t in FIXTURE_PATHS)
        if r < 0.35 and read:
            return rng.choice(read)  # an input of the command, directly or through a scene or pipeline
        if r < 0.5:
            others = output_values(argv)
            if others:
                return rng.choice(others)  # another output's path
        if r < 0.75:
            return rng.choice(SPECIAL_PATHS)
        return rng.choice(OUTPUT_TARGETS)
    return rng.choice(FIXTURE_PATHS if rng.random() < 0.6 else SPECIAL_PATHS)  # "in"


def mutate_structured(rng, argv):
    """One change that keeps the command line well formed: an option's value replaced, an
    option added with a value of its kind, or the command's input swapped."""
    argv = list(argv)
    command = command_of(argv)
    options = OPTIONS.get(command)
    if not options:
        return argv
    at = argv.index(command)
    r = rng.random()
    present = [i for i, t in enumerate(argv) if t in options and options[t] is not None and i + 1 < len(argv)]
    if r < 0.45 and present:
        i = rng.choice(present)
        argv[i + 1] = value_for(rng, options[argv[i]], argv)
    elif r < 0.85:
        flag = rng.choice(sorted(options))
        argv += [flag] if options[flag] is None else [flag, value_for(rng, options[flag], argv)]
    else:
        positional = [i for i in range(at + 1, len(argv)) if not argv[i].startswith("-") and
                      (i == at + 1 or not argv[i - 1].startswith("-") or options.get(argv[i - 1], 0) is None)]
        if positional:
            argv[rng.choice(positional)] = value_for(rng, "in", argv)
    return argv


def mutate(rng, argv, corpus):
    if rng.random() < STRUCTURED[0]:
        out = argv
        for _ in range(1 + int(rng.expovariate(1.5))):
            out = mutate_structured(rng, out)
        return [a.replace("\0", "") for a in out][:64]
    argv = list(argv)
    for _ in range(1 + int(rng.expovariate(1.0))):
        op = rng.random()
        if op < 0.35 and argv:
            i = rng.randrange(len(argv))
            argv[i] = mutate_token(rng, argv[i], argv)
        elif op < 0.55:
            argv.insert(rng.randrange(len(argv) + 1), random_token(rng, argv))
        elif op < 0.62 and argv:
            flag = rng.choice(FLAGS.get(command_of(argv), ["-o"]))
            argv += [flag, mutate_token(rng, "1", argv) if rng.random() < 0.5 else rng.choice(SPECIAL_PATHS)]
        elif op < 0.75 and argv:
            del argv[rng.randrange(len(argv))]
        elif op < 0.82 and len(argv) > 1:
            i, j = rng.randrange(len(argv)), rng.randrange(len(argv))
            argv[i], argv[j] = argv[j], argv[i]
        elif op < 0.88 and argv:
            i = rng.randrange(len(argv))
            argv.insert(i, argv[i])
        elif op < 0.94 and corpus:
            other = rng.choice(corpus)
            argv = argv[: rng.randrange(len(argv) + 1)] + other[rng.randrange(len(other) + 1):]
        elif argv:
            # A command swapped for another, its arguments kept (flags moved between commands).
            for i, t in enumerate(argv):
                if t in COMMANDS:
                    argv[i] = rng.choice(COMMANDS)
                    break
    return [a.replace("\0", "") for a in argv][:64]  # argv cannot hold a NUL (execve)


OUTPUT_OPTIONS = ("-o", "--output", "--png", "--stats", "--diff", "--report")
# What each fixture reads in turn (scenes their meshes, volumes and sources; pipelines their
# sources and scenes).
REFERENCES = {scene: ["hill.obj", "bush.vto", "bush.glb"] for scene in
              ["scene.toml", "far-camera.toml", "bright.toml", "shiny.toml", "big.toml", "nul-path.toml", "link.toml"]}
REFERENCES.update({"huge-mesh.toml": ["huge.obj", "bush.vto", "bush.glb"], "plain.toml": ["hill.obj"],
                   "pipeline.toml": ["bush.glb", "scene.toml"], "collide.toml": ["bush.glb", "scene.toml"]})


def output_values(argv):
    """The paths given as the value of an output option ("-o x" or "--output=x"), in order.
    CLI11 keeps the last of a repeated option: only distinct options count."""
    given = {}
    for i, token in enumerate(argv):
        if token in OUTPUT_OPTIONS and i + 1 < len(argv):
            given[token.replace("--output", "-o")] = argv[i + 1]
        elif "=" in token and token.split("=", 1)[0] in OUTPUT_OPTIONS:
            given[token.split("=", 1)[0].replace("--output", "-o")] = token.split("=", 1)[1]
    return [os.path.normpath(v) for v in given.values() if v]


def outputs_named(argv):
    return set(output_values(argv))


def inputs_named(argv):
    """Every other argument that names a file, and what those files read in turn."""
    outputs = {i + 1 for i, t in enumerate(argv) if t in OUTPUT_OPTIONS}
    todo = [os.path.normpath(t.split("=", 1)[-1]) for i, t in enumerate(argv) if i not in outputs]
    read = set()
    while todo:
        name = todo.pop()
        if name not in read:
            read.add(name)
            todo += REFERENCES.get(name, [])
    return read
