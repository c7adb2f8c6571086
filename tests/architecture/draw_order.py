#!/usr/bin/env python3
"""Refuses seeded random draws whose order the compiler chooses.

C++ leaves the order in which a call's arguments are evaluated unspecified: GCC evaluates them right to left, Clang
left to right. `glm::vec3(u(rng), u(rng), u(rng))` is therefore another vector under each compiler, and a seeded test
poses other cases in the GCC pass than in the sanitizer (Clang) pass: a failure seen in one cannot be replayed in the
other. A braced list is evaluated left to right (`glm::vec3{u(rng), u(rng), u(rng)}`), and so are separate statements.

This check finds parenthesised argument lists in which two or more arguments use a random generator of the file (a
name declared as a std::mt19937, mt19937_64, minstd_rand or default_random_engine, or a reference to one), other than
by passing the generator itself. Usage: draw_order.py ROOT (checks ROOT/tests and ROOT/bench), or --self-test.
"""
import pathlib
import re
import sys

ENGINE = re.compile(r"std::(?:mt19937(?:_64)?|minstd_rand0?|default_random_engine)\s*&?\s*(\w+)\s*[({;=,)]")


def strip(text):
    """Comments, string literals and preprocessor lines (`#include <random>`) blanked, line breaks kept, so that
    offsets still give line numbers."""
    text = re.sub(r"^[ \t]*#[^\n]*", lambda m: " " * len(m.group()), text, flags=re.M)
    text = re.sub(r"/\*.*?\*/", lambda m: re.sub(r"[^\n]", " ", m.group()), text, flags=re.S)
    text = re.sub(r"//[^\n]*", lambda m: " " * len(m.group()), text)
    return re.sub(r'"(?:\\.|[^"\\\n])*"', lambda m: '"' + " " * (len(m.group()) - 2) + '"', text)


def top_level_args(inner):
    depth, args, current = 0, [], ""
    for ch in inner:
        if ch in "({[":
            depth += 1
        elif ch in ")}]":
            depth -= 1
        if ch == "," and depth == 0:
            args.append(current)
            current = ""
        else:
            current += ch
    args.append(current)
    return args


def split_top(text, separators):
    """(offset, piece) of the pieces of `text` between `separators` (a compiled pattern) outside any bracket."""
    depth, pieces, start, i = 0, [], 0, 0
    while i < len(text):
        ch = text[i]
        if ch in "({[":
            depth += 1
        elif ch in ")}]":
            depth -= 1
        elif depth == 0:
            m = separators.match(text, i)
            if m:
                pieces.append((start, text[start:i]))
                start = i = m.end()
                continue
        i += 1
    pieces.append((start, text[start:]))
    return pieces


# Where C++17 sequences what comes before against what comes after: statements, the comma operator, ?:, && and ||,
# and assignments (the right side first); shifts (<<, >>) are sequenced too. What is left between them are operands
# whose order the compiler chooses.
SEQUENCED = re.compile(r";|,|\?|:|&&|\|\||<<|>>|[-+*/%&|^]?=(?!=)")
# Binary arithmetic: - but not ->, + but not ++ (increments draw nothing here).
OPERATOR = re.compile(r"\*|/(?![/*])|%|\+(?!\+)|-(?![->])")


def violations(text):
    """(line, excerpt) of each place where two or more draws run in an order the compiler chooses: the arguments of
    one parenthesised list, or the operands of one arithmetic expression."""
    text = strip(text)
    engines = set(ENGINE.findall(text))
    if not engines:
        return []
    uses = re.compile(r"\b(?:" + "|".join(sorted(engines)) + r")\b")

    def draws(piece):
        return uses.search(piece) and not uses.fullmatch(piece.strip())

    found, stack = [], []
    groups = [(0, len(text), "")]
    for i, ch in enumerate(text):
        if ch in "({[":
            stack.append((ch, i))
        elif ch in ")}]" and stack:
            opening, start = stack.pop()
            groups.append((start + 1, i, opening))
    for start, end, opening in groups:
        inner = text[start:end]
        if opening == "(" and sum(1 for a in top_level_args(inner) if draws(a)) >= 2:
            reason = start
        else:
            unordered = [at for at, seg in split_top(inner, SEQUENCED)
                         if sum(1 for _, o in split_top(seg, OPERATOR) if draws(o)) >= 2]
            if not unordered:
                continue
            reason = start + unordered[0] + len(inner[unordered[0]:]) - len(inner[unordered[0]:].lstrip())
        line = text.count("\n", 0, reason) + 1
        excerpt = " ".join(text[text.rfind("\n", 0, reason) + 1:text.find("\n", reason)].split())
        found.append((line, excerpt[:120]))
    return sorted(set(found))


def self_test():
    bad = [
        "std::mt19937 rng(1); auto v = glm::vec3(u(rng), u(rng), u(rng));",
        "void f(std::mt19937& random) { g(pick(random, 2), 3 + int(random() % 4)); }",
        "std::mt19937 r{7}; points.emplace_back(u(r), 0.0f, u(r));",
        "void f(std::mt19937& rng) { const float r = 3.5f * unit(rng) * unit(rng); }",
        "void f(std::mt19937& rng) { p += j(rng) * a + j(rng) * b; }",
    ]
    good = [
        "std::mt19937 rng(1); auto v = glm::vec3{u(rng), u(rng), u(rng)};",
        "std::mt19937 rng(1); const float x = u(rng); const float y = u(rng); f(x, y);",
        "std::mt19937 rng(1); points_inside(frame, rng, 1 + rng() % 40);",
        "std::mt19937 rng(1); f(g(rng), /* u(rng) */ 2);",
        "auto v = glm::vec3(u(other), u(other), 1.0f);  // no generator declared here",
        "void f(std::mt19937& rng) { a[rng() % 3] = float(rng() % 2); b = rng() % 4 == 0 ? rng() % 2 : 3; }",
        "void f(std::mt19937& rng) { if (rng() % 2 && rng() % 3) out << u(rng) << u(rng); }",
        "void f(std::mt19937* rng) { x = -u(*rng); p->q = 1; }",
    ]
    ok = all(violations(t) for t in bad) and not any(violations(t) for t in good)
    print("draw_order self-test:", "passed" if ok else "FAILED")
    return 0 if ok else 1


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    root = pathlib.Path(sys.argv[1])
    count = 0
    for folder in ("tests", "bench"):
        for path in sorted((root / folder).rglob("*.[ch]pp")):
            for line, excerpt in violations(path.read_text(encoding="utf-8")):
                print(f"{path.relative_to(root)}:{line}: random draws in an order the compiler chooses: {excerpt}")
                count += 1
    if count:
        print(f"{count} argument lists draw more than once; draw into variables or use a braced list")
        return 1
    print("draw_order: every seeded draw is in a fixed order")
    return 0


if __name__ == "__main__":
    sys.exit(main())
