#!/usr/bin/env python3
"""Holds a build to the engine's prefix: every header of GLM, nlohmann-json, Eigen and doctest that any compiled file
read came from PREFIX, none from anywhere else (the host's /usr/include above all).

    headers_from_prefix.py BUILD_DIR PREFIX [--require glm,nlohmann] [--ninja NINJA]

What a file read is what the compiler wrote in its dependency file: the `*.d` files beside the objects (CMake's
Makefile generators, GCC and Clang) or, for Ninja, `NINJA -t deps`. A header counts as a package's when its path has
the package's folder (glm/, nlohmann/, eigen3/ or Eigen/, doctest/) as a component. PREFIX must be a copy of the
packages, not links to the host's folders: GCC names a header reached through a link by its resolved path.
--require names packages some object must have read (so that a build that read none cannot pass).
Exit status: 0 when every such header is under PREFIX, 1 otherwise (each offending object and header printed).
"""
import argparse
import os
import pathlib
import subprocess
import sys

PACKAGES = {"glm": {"glm"}, "nlohmann": {"nlohmann"}, "eigen": {"eigen3", "Eigen"}, "doctest": {"doctest"}}


def depfile_inputs(text):
    """The prerequisites of a Makefile-style dependency file (escaped spaces kept, continuations joined)."""
    text = text.replace("\\\n", " ")
    inputs = []
    for rule in text.split("\n"):
        if ":" not in rule:
            continue
        # "target: a b c"; a Windows drive ("C:/x") never starts a rule written by GCC for a POSIX build folder.
        _, _, rest = rule.partition(": ")
        word, escaped = "", False
        for c in rest + " ":
            if escaped:
                word, escaped = word + c, False
            elif c == "\\":
                escaped = True
            elif c in " \t":
                if word:
                    inputs.append(word)
                word = ""
            else:
                word += c
    return inputs


def package_of(path):
    parts = set(pathlib.PurePosixPath(path).parts[:-1])
    for name, folders in PACKAGES.items():
        if parts & folders:
            return name
    return None


def check(objects, prefix, required):
    """objects: {object: [headers]}. Returns (problems, {package: objects that read it})."""
    prefixes = tuple({os.path.normpath(prefix) + os.sep, os.path.realpath(prefix) + os.sep})
    problems, seen = [], {name: 0 for name in PACKAGES}
    for obj, headers in objects.items():
        read = set()
        for header in headers:
            name = package_of(header)
            if name is None:
                continue
            read.add(name)
            if not os.path.normpath(header).startswith(prefixes):
                problems.append(f"{obj}: {header} is not in the engine's prefix")
        for name in read:
            seen[name] += 1
    for name in required:
        if not seen.get(name):
            problems.append(f"no object read a {name} header: the check saw nothing to check")
    return problems, seen


def self_check():
    """The check itself must be able to fail: a header from /usr/include, and a package no object read."""
    fake = {"a.o": ["/p/include/glm/glm.hpp", "/usr/include/glm/detail/setup.hpp"]}
    assert check(fake, "/p", ["glm"])[0], "a host GLM header went unnoticed"
    assert check({"a.o": ["/p/include/glm/glm.hpp"]}, "/p", ["nlohmann"])[0], "an unread package went unnoticed"
    assert not check({"a.o": ["/p/include/glm/glm.hpp", "/usr/include/stdio.h"]}, "/p", ["glm"])[0]
    assert depfile_inputs("x.o: a\\ b.h \\\n /c/glm/d.hpp\n") == ["a b.h", "/c/glm/d.hpp"]


def main():
    self_check()
    parser = argparse.ArgumentParser()
    parser.add_argument("build")
    parser.add_argument("prefix")
    parser.add_argument("--require", default="")
    parser.add_argument("--ninja")
    args = parser.parse_args()
    objects = {}
    if args.ninja:
        # Ninja runs every compiler in the build folder: relative paths start there.
        out = subprocess.run([args.ninja, "-C", args.build, "-t", "deps"], capture_output=True, text=True,
                             check=True).stdout
        current = None
        for line in out.split("\n"):
            if line and not line[0].isspace():
                current = line.split(":")[0]
                objects[current] = []
            elif line.strip() and current:
                objects[current].append(os.path.normpath(os.path.join(args.build, line.strip())))
    else:
        for depfile in pathlib.Path(args.build).rglob("*.d"):
            if depfile.suffixes[-2:-1] in ([".o"], [".obj"]) and "CMakeFiles" in depfile.parts:
                # The compiler ran in the target's folder, the one holding CMakeFiles/: relative paths start there.
                parts = depfile.parts
                cwd = pathlib.Path(*parts[:len(parts) - parts[::-1].index("CMakeFiles") - 1])
                objects[str(depfile)] = [os.path.normpath(os.path.join(cwd, header))
                                         for header in depfile_inputs(depfile.read_text(errors="replace"))]
    required = [r for r in args.require.split(",") if r]
    problems, seen = check(objects, args.prefix, required)
    for problem in problems:
        print(problem)
    counts = ", ".join(f"{name} {n}" for name, n in seen.items())
    print(f"{len(objects)} compiled files; those that read each package: {counts}; "
          f"{'all from' if not problems else 'NOT all from'} {args.prefix}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
