#!/usr/bin/env python3
"""Runs every command that README.md and docs/ show, so that the examples cannot rot.

    doc_commands.py SOURCE_DIR DEFORM_BINARY MAKE_BUILTIN_BINARY WORK_DIR

Two kinds of fenced blocks are run; the others (```text synopses, ```json, ```cpp, ```cmake) are not:
  ```sh        every line is a command (a trailing backslash continues it); each must exit 0.
  ```console   lines starting with "$ " are commands; the lines after one, up to the next "$ ", are its expected
               output (stdout and stderr together). "..." in the expected text stands for any text, within a line or
               across lines, so a page can show the start of a long output. The command must exit 0 unless its
               expected output is empty and the block says `# exit N` after it.
Commands run with bash in WORK_DIR, a scratch folder holding `samples/` (a copy: commands may write there),
`tests/` (a link to the sources), `build/tools/deform`, `build/tools/make_builtin` and `build/tools/motion_study`
(links to the binaries), with
`deform` on PATH. A few commands are not run here, each for a stated reason (see NOT_RUN); every other one is.
Python (docs/python.md): when the environment names the built module's folder (DEFORM_PYTHON_MODULE_DIR) and the
interpreter the build found (DEFORM_PYTHON), WORK_DIR also holds `python/` (a link to the sources) and
`build/python` (a link to that folder), and `python3` on PATH is that interpreter; without them, commands that use
`build/python` are not run (the module is not built in that configuration, e.g. under the sanitizers).
Exit status: 0 when every command behaved as shown, 1 otherwise (each failure printed).
"""
import os
import pathlib
import re
import shutil
import subprocess
import sys

# Commands the suite runs in other ways, by prefix: never skipped silently, always listed in the report.
NOT_RUN = {
    "./scripts/test": "it is the suite that runs this test",
    "./scripts/demo": "the viewer under Xvfb is the viewer_smoke_xvfb test, the CLI half the commands below",
    "./scripts/web": "it serves until stopped; scripts/test builds the page and opens it in headless Chromium",
    "./scripts/fuzz": "the suite runs every fuzzer for a fixed number of inputs (the fuzz_* tests)",
    "./scripts/format": "it rewrites the sources; the source_format test runs it with --check",
    "cmake ": "the build itself: scripts/test builds, consumer_links_installed_library installs and links",
    "cc ": "a C program built against the installed package: consumer_links_installed_library builds it so",
    "python3 -m pip install": "it builds the whole library through CMake (minutes); docs/python.md says how it was checked",
    "python3 tools/motion_study/plot.py": "the motion_study_plot test runs it with the interpreter that has matplotlib",
}


def pages(source):
    root = pathlib.Path(source)
    found = [root / "README.md"] + sorted((root / "docs").glob("*.md")) + [root / "samples" / "README.md"]
    found += sorted((root / "samples").glob("*/README.md"))
    return [p for p in found if p.exists()]


def blocks(text):
    """(language, first line number, body lines) of every fenced block."""
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        m = re.match(r"^```(\w*)\s*$", lines[i])
        if not m:
            i += 1
            continue
        start = i + 1
        j = start
        while j < len(lines) and not lines[j].startswith("```"):
            j += 1
        yield m.group(1), start + 1, lines[start:j]
        i = j + 1


def join_continued(lines):
    out, current = [], ""
    for line in lines:
        if line.rstrip().endswith("\\"):
            current += line.rstrip()[:-1] + " "
            continue
        out.append(current + line)
        current = ""
    return [c for c in out if c.strip() and not c.lstrip().startswith("#")]


def matches(expected, actual):
    """True when `actual` is `expected` with each "..." standing for any text (trailing blanks ignored)."""
    norm = lambda s: "\n".join(l.rstrip() for l in s.strip("\n").split("\n"))
    parts = norm(expected).split("...")
    pattern = ".*?".join(re.escape(p) for p in parts)
    return re.fullmatch(pattern, norm(actual), re.S) is not None


def skipped(command):
    if "build/python" in command and not os.environ.get("DEFORM_PYTHON_MODULE_DIR"):
        return "the Python module is not built in this configuration"
    for prefix, reason in NOT_RUN.items():
        if command.lstrip().startswith(prefix):
            return reason
    return None


def check_matcher():
    """The comparison itself must be able to fail: a few cases it must accept and reject."""
    assert matches("a ...\nz", "a b\nc\nz")
    assert matches('{"n": ...}', '{"n": 3}\n')
    assert not matches('{"n": 3}', '{"n": 4}')
    assert not matches("line one\n...\nlast", "line one\nmiddle\nnot last")


def main():
    check_matcher()
    source, deform, make_builtin, work = (os.path.abspath(a) for a in sys.argv[1:5])
    work = pathlib.Path(work)
    shutil.rmtree(work, ignore_errors=True)
    (work / "bin").mkdir(parents=True)
    (work / "build" / "tools").mkdir(parents=True)
    shutil.copytree(pathlib.Path(source) / "samples" / "data", work / "samples" / "data")
    os.symlink(pathlib.Path(source) / "tests", work / "tests")
    os.symlink(deform, work / "bin" / "deform")
    os.symlink(deform, work / "build" / "tools" / "deform")
    if os.path.exists(make_builtin):
        os.symlink(make_builtin, work / "build" / "tools" / "make_builtin")
    study = pathlib.Path(deform).parent / "motion_study"  # built beside the CLI (tools/CMakeLists.txt)
    if study.exists():
        os.symlink(study, work / "build" / "tools" / "motion_study")
    module_dir, python = os.environ.get("DEFORM_PYTHON_MODULE_DIR"), os.environ.get("DEFORM_PYTHON")
    if module_dir and python:
        os.symlink(pathlib.Path(source) / "python", work / "python")
        os.symlink(module_dir, work / "build" / "python")
        os.symlink(python, work / "bin" / "python3")
    env = dict(os.environ, PATH=f"{work / 'bin'}:{os.environ['PATH']}", MPLBACKEND="Agg")

    failures, ran, not_run = [], 0, []

    def run(command, where):
        nonlocal ran
        reason = skipped(command)
        if reason:
            not_run.append(f"{where}: `{command.strip()}`: {reason}")
            return None
        ran += 1
        result = subprocess.run(["bash", "-c", command], cwd=work, env=env, capture_output=True, text=True,
                                timeout=300)
        return result

    for page in pages(source):
        name = page.relative_to(source)
        for language, line, body in blocks(page.read_text()):
            if language == "sh":
                for command in join_continued(body):
                    result = run(command, f"{name}:{line}")
                    if result is not None and result.returncode != 0:
                        failures.append(f"{name}:{line}: `{command}` exited {result.returncode}:\n"
                                        f"{result.stdout}{result.stderr}")
            elif language == "console":
                command, expected = None, []
                pending = []
                for text in body + ["$ "]:
                    if text.startswith("$ "):
                        if command is not None:
                            pending.append((command, "\n".join(expected)))
                        command, expected = text[2:], []
                    else:
                        expected.append(text)
                for command, want in pending:
                    result = run(command, f"{name}:{line}")
                    if result is None:
                        continue
                    got = result.stdout + result.stderr
                    if result.returncode != 0:
                        failures.append(f"{name}:{line}: `{command}` exited {result.returncode}:\n{got}")
                    elif want.strip() and not matches(want, got):
                        failures.append(f"{name}:{line}: `{command}` printed something else than the page shows."
                                        f"\n--- page:\n{want}\n--- printed:\n{got}")

    for entry in not_run:
        print(f"not run here: {entry}")
    for failure in failures:
        print(f"FAILED {failure}\n")
    print(f"{ran - len(failures)} passed, {len(failures)} failed")
    return 1 if failures or ran == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
