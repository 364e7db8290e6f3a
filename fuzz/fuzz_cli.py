#!/usr/bin/env python3
"""Command-line fuzzing of `vtex`: the arguments are the fuzzed input.

A black-box, mutation-based driver (Python 3 standard library only). It starts from a seed
corpus of command lines (corpus-cli/, one argv per file as a JSON array of strings), mutates
them (tokens replaced, inserted, deleted, swapped; numbers swapped for nan/inf/-0/1e308/huge/
negative/empty; flags moved between commands; paths swapped for a FIFO, a device, a directory,
the command's own input, a missing file, a link loop, a very long name) and runs the vtex under
test, ideally built with ASan and UBSan (cmake -DVTEX_SANITIZE=ON), in a fresh scratch folder
of small fixture inputs, with a per-run timeout and a resident-memory limit.

Why not libFuzzer in process: a command is a whole program (threads, exit paths, files written
atomically, signals, the exit status main() maps) and may legitimately run for minutes; what is
checked is what a user sees from outside. An in-process target would need main() refactored and
every run to reset global state (TBB, CLI11's registry, static caches).

Outcomes (fuzz/README.md, "fuzz_cli"):
  finding  a signal or abort, a sanitizer report, an exit status outside {0, 1, 2, 3}, a non-zero
           exit whose last line (before the usage hint) is not one `vtex: error:` line, a raw
           library message (std::filesystem, std::sto*, basic_string, ...), a fixture changed,
           replaced or removed, a leftover `.tmp.` file, an output left behind by a refused
           command (exit 2 or 3; and exit 1 of any command but run and demo, whose finished
           stages stay valid), a run over the memory limit.
  timeout  logged separately (timeouts/); each is to be examined: a large but legal amount of
           work within the memory limit is not a bug, a hang on a tiny input is.

The fixtures are in cli_fixtures.py, the mutations and what an argv names in cli_mutate.py.

Usage:
  python3 fuzz/fuzz_cli.py --vtex build-asan/apps/vtex/vtex --work /tmp/fuzz-cli --time 3600
  python3 fuzz/fuzz_cli.py --vtex ... --work ... --replay       # the seeds only, once each
  python3 fuzz/fuzz_cli.py --vtex ... --work ... --show FILE    # run one argv file, print all
"""

import argparse
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import time

import cli_mutate  # fuzz/cli_mutate.py and fuzz/cli_fixtures.py, beside this file (sys.path[0])
from cli_fixtures import make_fixtures, populate, snapshot
from cli_mutate import command_of, inputs_named, mutate, output_values, outputs_named

HERE = os.path.dirname(os.path.abspath(__file__))

BASELINE = [256 << 20]  # resident memory of the vtex under test doing nothing, plus a margin (measured)


# ---------------------------------------------------------------------------------------------
# Running and classifying.

SANITIZER = re.compile(r"ERROR: AddressSanitizer|ERROR: LeakSanitizer|runtime error:|UndefinedBehaviorSanitizer|"
                       r"AddressSanitizer:DEADLYSIGNAL|terminate called|Assertion .* failed")
RAW_LIBRARY = re.compile(r"filesystem error|basic_string|std::|vector::|map::at|\bsto(i|l|ul|ull|d|f)\b|bad_alloc|"
                         r"_M_|bad_optional|bad_variant|out_of_range|invalid_argument|nlohmann|json\.exception|"
                         r"\bIex_|Iex::|toml::")
USAGE_HINT = "Run 'vtex --help' or 'vtex <command> --help' for usage."


def rss_of_tree(pid):
    """Resident memory of `pid` and its descendants, bytes."""
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        try:
            with open(f"/proc/{p}/status") as f:
                for line in f:
                    if line.startswith("VmRSS:"):
                        total += int(line.split()[1]) * 1024
            with open(f"/proc/{p}/task/{p}/children") as f:
                todo += [int(c) for c in f.read().split()]
        except (OSError, ValueError):
            pass
    return total


def run_once(vtex, argv, run_dir, env, timeout, rss_limit):
    started = time.monotonic()
    peak = 0
    with open(os.path.join(run_dir, "..", "stdout.txt"), "wb") as out, \
            open(os.path.join(run_dir, "..", "stderr.txt"), "wb") as err:
        proc = subprocess.Popen([vtex, *argv], cwd=run_dir, env=env, stdin=subprocess.DEVNULL, stdout=out,
                                stderr=err, start_new_session=True)
        verdict = None
        while True:
            try:
                proc.wait(timeout=0.05)
                break
            except subprocess.TimeoutExpired:
                pass
            peak = max(peak, rss_of_tree(proc.pid))
            if peak > rss_limit:
                verdict = "memory"
            elif time.monotonic() - started > timeout:
                verdict = "timeout"
            if verdict:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
                break
    with open(os.path.join(run_dir, "..", "stderr.txt"), "rb") as f:
        stderr = f.read().decode("utf-8", "replace")
    stderr = "\n".join(l for l in stderr.split("\n") if not l.startswith("\t0x"))  # ASan's memory map
    with open(os.path.join(run_dir, "..", "stdout.txt"), "rb") as f:
        stdout = f.read(4096).decode("utf-8", "replace")
    return proc.returncode, stdout, stderr, verdict, time.monotonic() - started, peak


def error_line_problem(status, stderr):
    """Why the stderr of a failed command is not one `vtex: error:` line, or None."""
    lines = [l for l in stderr.split("\n")]
    while lines and lines[-1] == "":
        lines.pop()
    if lines and lines[-1] == USAGE_HINT and status == 2:
        lines.pop()
    errors = [l for l in lines if l.startswith("vtex: error: ")]
    if not lines or not lines[-1].startswith("vtex: error: "):
        return "the last line is not a 'vtex: error:' line"
    if len(errors) != 1:
        return f"{len(errors)} 'vtex: error:' lines"
    return None


def size_value(text):
    """Bytes of a CLI11 size ("512MB", "4GiB", "1024"; k = 1024 as vtex's AsSizeValue(false)),
    or None."""
    m = re.fullmatch(r"\s*(\d+(?:\.\d*)?)\s*([kmgt]?)(i?)b?\s*", text.lower())
    if not m:
        return None
    return float(m.group(1)) * 1024 ** " kmgt".index(m.group(2) or " ")


# The commands that estimate their peak memory and refuse work over --max-memory SIZE, which
# defaults to half of the machine's memory (core/memory_budget.h).
BUDGETED = ("sample", "build", "render", "reference", "run")
OVER_LIMIT = "resident memory over the limit"


def max_memory_at(argv):
    """Index of the value of `--max-memory VALUE` (or of the `--max-memory=VALUE` token), or None."""
    for i, token in enumerate(argv):
        if token == "--max-memory" and i + 1 < len(argv):
            return i + 1
        if token.startswith("--max-memory="):
            return i
    return None


def promised_memory(argv):
    """The memory a budgeted command was told it may use, bytes, or None (not given, 0: no
    limit, or not a size). Since main's 2f4ab27 every budgeted command takes a size; the
    reference's --max-memory is no longer GiB of its deformed mode."""
    at = max_memory_at(argv)
    if command_of(argv) not in BUDGETED or at is None:
        return None
    v = size_value(argv[at].split("=", 1)[-1] if argv[at].startswith("--max-memory=") else argv[at])
    return v if v else None


def told_the_limit(argv, cap):
    """argv with its --max-memory set to `cap` bytes (CLI11 refuses the option twice)."""
    argv = list(argv)
    at = max_memory_at(argv)
    if at is None:
        return argv + ["--max-memory", str(cap)]
    argv[at] = f"--max-memory={cap}" if argv[at].startswith("--max-memory=") else str(cap)
    return argv


def budget_verdict(argv, findings, execute_once, cap):
    """A budgeted command over this campaign's memory limit is not a bug in itself: vtex's own
    default limit (half the machine's memory, 11.8 GiB on the 2-core test machine) is above the
    campaign's, and `render --width 16384 --height 16384` (5.3 GiB, its estimate) is legal work
    there; the first two campaigns flagged dozens of such runs. So the run is made again, told the
    campaign's limit less the program's own size: refused at once with its estimate (exit 3,
    "needs about"), it was such work ("budget", logged with the timeouts); over the limit again,
    vtex's estimate undercounts, which is a finding."""
    if command_of(argv) not in BUDGETED or ("memory", OVER_LIMIT) not in findings:
        return findings
    promised = promised_memory(argv)
    if promised is not None and promised <= cap:
        return findings  # told less than the limit, and went over it anyway
    status, _, stderr, verdict, _, peak, again = execute_once(told_the_limit(argv, cap))
    rest = [f for f in findings if f != ("memory", OVER_LIMIT)]
    if status == 3 and "needs about" in stderr:
        return rest + [("budget", f"refused with its estimate once told --max-memory {cap >> 20} MiB")]
    if ("memory", OVER_LIMIT) in again:
        return rest + [("memory", f"over the limit even when told --max-memory {cap >> 20} MiB "
                                  f"(peak {peak >> 20} MiB)")]
    return rest + [("memory", f"over the limit; told --max-memory {cap >> 20} MiB it ended with {status} "
                              f"{verdict or ''}: to examine")]


def classify(argv, status, stdout, stderr, verdict, before, after, peak=0):
    """(category, reason) of findings; [] when the run is fine. A timeout is its own category."""
    findings = []
    if verdict == "timeout":
        return [("timeout", "over the per-run time limit")]
    asan_rss = "hard rss limit exhausted" in stderr  # ASan's own watch on the same limit (exit 86)
    if verdict == "memory" or asan_rss:
        findings.append(("memory", OVER_LIMIT))
    promised = promised_memory(argv)
    # Only a run that did the work; on top of the promise, the program's own resident size
    # (an ASan Debug vtex is ~180 MiB before it does anything) and ASan's shadow, redzones and
    # quarantine: twice the promise and BASELINE.
    if promised and status == 0 and peak > 2 * promised + BASELINE[0]:
        findings.append(("memory", f"peak {peak >> 20} MiB, over its --max-memory of {int(promised) >> 20} MiB"))
    if SANITIZER.search(stderr):
        findings.append(("sanitizer", SANITIZER.search(stderr).group(0)))
    if verdict is None and status < 0:
        findings.append(("signal", f"killed by signal {-status}"))
    if verdict is None and status not in (0, 1, 2, 3) and status >= 0 and not asan_rss:
        findings.append(("status", f"exit status {status}"))
    if verdict is None and status in (1, 2, 3) and not asan_rss:
        problem = error_line_problem(status, stderr)
        if problem:
            findings.append(("message", problem))
    for line in stderr.split("\n"):
        if line.startswith("vtex: error: ") and RAW_LIBRARY.search(line):
            findings.append(("message", "a library's own message: " + line[:200]))
            break
    named = output_values(argv)
    helped = any(t in ("-h", "--help", "--version") for t in argv)  # help printed, nothing run
    if status == 0 and not helped and len(named) != len(set(named)):
        findings.append(("output", "one path given for two outputs, and the command succeeded"))
    if status == 0 and "vtex: error:" in stderr:
        findings.append(("message", "exit 0 with an error message"))
    asked = outputs_named(argv)
    read = inputs_named(argv)
    for name, entry in before.items():
        if name in asked and name not in read:
            continue  # the user named it as an output: replacing it is what was asked for
        if name not in after:
            findings.append(("fixture", f"{name} removed"))
        elif after[name] != entry:
            findings.append(("fixture", f"{name} changed or replaced"))
    new = sorted(set(after) - set(before))
    # A leftover temporary is named ".<output>.tmp.<host>.<pid>…"; an output the user named with
    # ".tmp." in it (`-o out.glb.tmp.x`, third campaign) is not one.
    tmp = [n for n in new if ".tmp." in os.path.basename(n) and n not in asked]
    if tmp:
        findings.append(("tmp", "left " + ", ".join(tmp[:5])))
    command = command_of(argv)
    outputs = [n for n in new if n not in tmp]
    # run and demo keep the stages that finished when one fails (exit 1), and when one is
    # refused as bad input once running (exit 3: `run … --max-memory 1`, whose sample stages are
    # refused by their estimates after the sources ran; third campaign), which is when they write
    # their report. A pipeline refused when read leaves nothing (regression_1).
    staged = command in ("run", "demo") and any(os.path.basename(n) == "report.json" for n in outputs)
    refused = status == 2 or (status == 3 and not staged) or (status == 1 and command not in ("run", "demo"))
    if verdict is None and refused and outputs:
        findings.append(("output", f"exit {status} left " + ", ".join(outputs[:5])))
    return findings


def signature(argv, status, stderr, verdict):
    """What a run did, coarsely: new signatures keep an input in the working corpus."""
    command = command_of(argv)
    last = [l for l in stderr.split("\n") if l.startswith("vtex: error: ")]
    message = last[-1][len("vtex: error: "):] if last else ""
    if status == 2:
        # Usage errors quote the arguments back: keep the options named and the first words
        # only, or every mutation would look new and the corpus would fill with them.
        words = [w for w in re.findall(r"[A-Za-z][A-Za-z-]*", message) if not w.startswith("-")][:5]
        options = sorted(set(re.findall(r"(?<![\w-])--?[a-z][a-z-]*", message)))[:3]
        message = " ".join(words + options)
    else:
        message = re.sub(r"[-+]?\d[\d.e+-]*", "N", message)
        message = re.sub(r"'[^']*'|\"[^\"]*\"", "Q", message)
        message = re.sub(r"\S*/\S*", "P", message)
    return f"{command}|{status}|{verdict}|{message[:120]}"


def examine(args, execute, work):
    """Each timeout, budget run and memory finding once more, with the given vtex and limits:
    what it needs without the sanitizers, and whether it finishes."""
    cases = []
    for folder, prefix in (("timeouts", "timeout-"), ("timeouts", "budget-"), ("findings", "memory-")):
        path = os.path.join(work, folder)
        for name in sorted(os.listdir(path)) if os.path.isdir(path) else []:
            if name.startswith(prefix):
                with open(os.path.join(path, name)) as f:
                    record = json.load(f)
                if record["argv"] not in [c["argv"] for c in cases]:
                    cases.append({"argv": record["argv"], "campaign": name})
    for case in cases:
        status, _, stderr, verdict, seconds, peak, findings = execute(case["argv"])
        last = [l for l in stderr.split("\n") if l.startswith("vtex: ")]
        case.update(status=status, verdict=verdict, seconds=round(seconds, 1), peak_rss_mb=peak >> 20,
                    findings=[c for c, _ in findings], last=last[-1][:200] if last else "")
        print(json.dumps(case), flush=True)
    with open(os.path.join(work, "examined.json"), "w") as f:
        json.dump(cases, f, indent=1)
    return 0


def recheck(folders, execute, work):
    """Every finding of earlier campaigns (their findings/ folders) once more with the vtex under
    test: what each does now. Grouped by the old category and reason; writes rechecked.json."""
    cases = {}
    for folder in folders:
        path = os.path.join(folder, "findings")
        for name in sorted(os.listdir(path)) if os.path.isdir(path) else []:
            with open(os.path.join(path, name)) as f:
                record = json.load(f)
            key = json.dumps(record["argv"])
            case = cases.setdefault(key, {"argv": record["argv"], "flags": []})
            case["flags"].append(f"{os.path.basename(folder)}/{name}: {record['status']} {record['reason'][:120]}")
    for case in cases.values():
        status, _, stderr, verdict, seconds, peak, findings = execute(case["argv"])
        last = [l for l in stderr.split("\n") if l.startswith("vtex: ")]
        case.update(status=status, verdict=verdict, seconds=round(seconds, 1), peak_rss_mb=peak >> 20,
                    findings=findings, last=last[-1][:300] if last else "")
        print(json.dumps(case), flush=True)
    with open(os.path.join(work, "rechecked.json"), "w") as f:
        json.dump(list(cases.values()), f, indent=1)
    return 1 if any(c not in ("timeout", "budget") for case in cases.values() for c, _ in case["findings"]) else 0


def pick(rng, corpus, usage):
    """A parent to mutate: one that ended in a usage error (exit 2) a fifth as often."""
    while True:
        argv = rng.choice(corpus)
        if json.dumps(argv) not in usage or rng.random() < 0.2:
            return argv


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vtex", required=True, help="the vtex under test (an ASan+UBSan build)")
    ap.add_argument("--seeds", default=os.path.join(HERE, "corpus-cli"))
    ap.add_argument("--work", required=True, help="scratch folder: fixtures, runs, corpus, findings")
    ap.add_argument("--time", type=float, default=600, help="campaign wall time, seconds")
    ap.add_argument("--runs", type=int, default=0, help="stop after this many runs (0: no limit)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--structured", type=float, default=0.6,
                    help="share of structure-keeping mutations (an option's value, an option added)")
    ap.add_argument("--timeout", type=float, default=20, help="per run, seconds")
    ap.add_argument("--rss-mb", type=int, default=3072, help="resident-memory limit per run, MiB")
    ap.add_argument("--fresh", action="store_true", help="empty the work folder first (fixtures made again)")
    ap.add_argument("--replay", action="store_true", help="run every seed once, no mutation")
    ap.add_argument("--show", help="run one argv file (JSON) and print everything")
    ap.add_argument("--examine", action="store_true",
                    help="run every command line of --work's timeouts and memory findings again (e.g. with a "
                         "Release vtex, a longer --timeout and a larger --rss-mb) and write examined.json")
    ap.add_argument("--recheck", nargs="+", metavar="CAMPAIGN",
                    help="run every finding of these earlier campaigns' work folders again and write "
                         "rechecked.json into --work (exit 1 if any is still a finding)")
    ap.add_argument("--fail-on-findings", action="store_true",
                    help="exit 1 when a run is a finding (not a timeout or a budget run; the smoke run)")
    args = ap.parse_args()

    cli_mutate.STRUCTURED[0] = args.structured
    vtex = os.path.abspath(args.vtex)
    work = os.path.abspath(args.work)
    if args.fresh and os.path.exists(work):
        shutil.rmtree(work)
    os.makedirs(work, exist_ok=True)
    env = dict(os.environ)
    env["ASAN_OPTIONS"] = ("detect_leaks=1:abort_on_error=0:exitcode=86:quarantine_size_mb=64:"
                           f"hard_rss_limit_mb={args.rss_mb}:allocator_may_return_null=0")
    env["UBSAN_OPTIONS"] = "print_stacktrace=1:halt_on_error=1:exitcode=87"
    env.pop("VTEX_DEBUG", None)

    pristine = os.path.join(work, "fixtures")
    specials_file = os.path.join(pristine, "specials.json")
    if os.path.exists(specials_file):
        with open(specials_file) as f:
            specials = json.load(f)
    else:
        specials = make_fixtures(vtex, pristine, env)
    run_dir = os.path.join(work, "run", "scratch")
    os.makedirs(os.path.dirname(run_dir), exist_ok=True)

    def execute_once(argv):
        populate(pristine, run_dir, specials)
        before = snapshot(run_dir)
        status, stdout, stderr, verdict, seconds, peak = run_once(vtex, argv, run_dir, env, args.timeout,
                                                                  args.rss_mb << 20)
        after = snapshot(run_dir)
        return status, stdout, stderr, verdict, seconds, peak, classify(argv, status, stdout, stderr, verdict,
                                                                        before, after, peak)

    def execute(argv):
        status, stdout, stderr, verdict, seconds, peak, findings = execute_once(argv)
        findings = budget_verdict(argv, findings, execute_once, (args.rss_mb << 20) - BASELINE[0])
        return status, stdout, stderr, verdict, seconds, peak, findings

    # The program's own resident size, measured on `vtex --version`, plus 128 MiB.
    _, _, _, _, _, idle, _ = execute(["--version"])
    BASELINE[0] = idle + (128 << 20)

    if args.show:
        with open(args.show) as f:
            argv = json.load(f)
        status, stdout, stderr, verdict, seconds, peak, findings = execute(argv)
        print(json.dumps({"argv": argv, "status": status, "verdict": verdict, "seconds": round(seconds, 2),
                          "peak_rss_mb": peak >> 20, "findings": findings}, indent=1))
        print("--- stdout\n" + stdout + "--- stderr\n" + stderr[-6000:])
        return 1 if findings else 0

    if args.examine:
        return examine(args, execute, work)
    if args.recheck:
        return recheck([os.path.abspath(f) for f in args.recheck], execute, work)

    seeds = []
    for name in sorted(os.listdir(args.seeds)):
        with open(os.path.join(args.seeds, name)) as f:
            seeds.append((name, json.load(f)))
    corpus_dir = os.path.join(work, "corpus")
    os.makedirs(corpus_dir, exist_ok=True)
    corpus = [argv for _, argv in seeds]
    for name in sorted(os.listdir(corpus_dir)):
        with open(os.path.join(corpus_dir, name)) as f:
            corpus.append(json.load(f))

    rng = random.Random(args.seed)
    usage = set()  # corpus entries (as JSON) that ended in a usage error: mutated less often
    stats_file = os.path.join(work, "stats.json")
    stats = {"runs": 0, "seconds": 0.0, "corpus": len(corpus), "signatures": 0, "findings": {}, "timeouts": 0,
             "statuses": {}}
    signatures = set()
    found = set()  # (category, reason-without-numbers, command): each kind of finding once
    start = time.monotonic()
    log = open(os.path.join(work, "log.txt"), "a")
    queue = list(corpus) if not args.replay else [argv for _, argv in seeds]
    replay_names = [name for name, _ in seeds]
    any_finding = False
    while True:
        elapsed = time.monotonic() - start
        if args.replay and not queue:
            break
        if not args.replay and (elapsed > args.time or (args.runs and stats["runs"] >= args.runs)):
            break
        argv = queue.pop(0) if queue else mutate(rng, pick(rng, corpus, usage), corpus)
        status, stdout, stderr, verdict, seconds, peak, findings = execute(argv)
        stats["runs"] += 1
        key = "timeout" if verdict == "timeout" else str(status)
        stats["statuses"][key] = stats["statuses"].get(key, 0) + 1
        sig = signature(argv, status, stderr, verdict)
        if sig not in signatures:
            signatures.add(sig)
            if not args.replay and argv not in corpus:
                corpus.append(argv)
                if status == 2:
                    usage.add(json.dumps(argv))
                with open(os.path.join(corpus_dir, f"{len(corpus):06d}.json"), "w") as f:
                    json.dump(argv, f)
        record = {"argv": argv, "status": status, "verdict": verdict, "seconds": round(seconds, 2),
                  "peak_rss_mb": peak >> 20, "findings": findings, "stderr": stderr[-4000:]}
        label = replay_names.pop(0) + " " if args.replay else ""
        log.write(f"{stats['runs']} {label}{json.dumps(argv)} -> {status} {verdict or ''} {seconds:.1f}s "
                  f"{[c for c, _ in findings]}\n")
        log.flush()
        for category, reason in findings:
            # Timeouts and runs refused by their own memory estimate once told the limit
            # (budget_verdict) are logged apart, to examine, and are not findings.
            folder = os.path.join(work, "timeouts" if category in ("timeout", "budget") else "findings")
            os.makedirs(folder, exist_ok=True)
            if category in ("timeout", "budget"):
                counter = "timeouts" if category == "timeout" else "budget"
                stats[counter] = stats.get(counter, 0) + 1
                n = stats[counter]
            else:
                # A 16384² render needs gigabytes legitimately; budget_verdict tells it apart (a
                # "budget" run, above), so what is left over the limit is a finding too.
                any_finding = True
                stats["findings"][category] = stats["findings"].get(category, 0) + 1
                n = sum(stats["findings"].values())
                kind = (category, re.sub(r"\d+", "N", reason), command_of(argv))
                if kind not in found:
                    found.add(kind)
                    print(f"finding [{category}] {reason}: vtex {' '.join(json.dumps(a) for a in argv)}",
                          flush=True)
            with open(os.path.join(folder, f"{category}-{n:05d}.json"), "w") as f:
                json.dump(dict(record, reason=reason), f, indent=1)
        if stats["runs"] % 50 == 0 or args.replay:
            stats.update(seconds=round(time.monotonic() - start, 1), corpus=len(corpus), signatures=len(signatures),
                         kinds=len(found))
            with open(stats_file, "w") as f:
                json.dump(stats, f, indent=1)
    stats.update(seconds=round(time.monotonic() - start, 1), corpus=len(corpus), signatures=len(signatures),
                 kinds=len(found))
    with open(stats_file, "w") as f:
        json.dump(stats, f, indent=1)
    print(json.dumps(stats))
    return 1 if (args.fail_on_findings and any_finding) else 0


if __name__ == "__main__":
    sys.exit(main())
