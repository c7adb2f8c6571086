#!/usr/bin/env python3
"""Fails on any #include that crosses a wall the wrong way (docs/architecture.md, "Walls").

    include_walls.py ROOT

ROOT is a source tree laid out as this project's. Every #include of the files under libdeform/include, libdeform/src,
bench and fixtures is resolved as the compiler would (the including file's folder, then the owner's private include
folders) and refused when
  - a layer includes the public header of a layer it does not use (LAYERS below);
  - a layer includes another layer's private header (src/<other>/...);
  - a public header includes a private one (src/..., the base);
  - the base includes anything but itself and runtime's public headers;
  - a benchmark includes a test's header (tests/...) or the library's private ones, or a fixture includes either.
LAYERS is also held against the layers' CMakeLists.txt: each deform_<layer> target must link exactly the layers the
table says it uses, and every folder of libdeform/src and libdeform/include/deform must be a layer (or the base).
Exit status 0 when nothing is refused, 1 otherwise (each refusal printed as FILE:LINE: reason).
"""
import pathlib
import re
import sys

# The layers in the order of docs/architecture.md, each with the layers it uses (its target's deform_* links).
LAYERS = {
    "runtime": (),
    "offline": ("runtime",),
    "io": ("runtime", "offline"),
    "character": ("runtime", "offline"),
    "extras": ("runtime", "offline", "character"),
    "import": ("runtime", "io"),
    "c": ("runtime", "offline", "io", "character", "extras", "import"),  # import: optional, when it is built
    "simplify": ("runtime", "offline"),
    "gpu": ("runtime",),
}
BASE = "base"  # libdeform/src/base: private to the library, included by every layer (bare names: "finite.hpp")
BASE_USES = ("runtime",)  # the base sits on runtime's public headers
UMBRELLA_USES = ("runtime", "offline", "io", "character", "extras")  # deform/deform.hpp: the deform::deform target
# Headers CMake writes into the build tree: deform/<layer>/export.hpp (each layer's own) and deform/version.hpp.
GENERATED_EXPORT = re.compile(r"deform/([a-z_]+)/export\.hpp")
EVERYONE = "deform/version.hpp"

SOURCE_SUFFIXES = {".h", ".hpp", ".inl", ".c", ".cpp"}
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^">]+)[">]')


class Walls:
    def __init__(self, root):
        self.root = pathlib.Path(root).resolve()
        self.include = self.root / "libdeform" / "include"
        self.src = self.root / "libdeform" / "src"
        self.problems = []

    def refuse(self, path, line, reason):
        self.problems.append(f"{path.relative_to(self.root)}:{line}: {reason}")

    def owner(self, path):
        """(kind, layer) of a file: ("public", L), ("private", L), ("base", None), ("umbrella", None),
        ("bench", None), ("fixtures", None), ("tests", None) or ("other", None)."""
        rel = path.relative_to(self.root).parts
        if rel[:3] == ("libdeform", "include", "deform"):
            return ("public", rel[3]) if len(rel) > 4 else ("umbrella", None)
        if rel[:2] == ("libdeform", "src") and len(rel) > 3:
            return ("base", None) if rel[2] == BASE else ("private", rel[2])
        if rel[0] in ("bench", "fixtures", "tests"):
            return (rel[0], None)
        return ("other", None)

    def uses(self, kind, layer):
        """The layers whose public headers a file of this owner may include."""
        if kind in ("public", "private"):
            return {layer, *LAYERS.get(layer, ())}
        if kind == "base":
            return set(BASE_USES)
        if kind == "umbrella":
            return set(UMBRELLA_USES)
        return set(LAYERS)  # bench, fixtures: any public header

    def private_folders(self, kind, layer):
        """The folders on a file's private include path, searched after its own folder."""
        if kind == "private":
            return [self.src / layer, self.src / BASE]
        if kind == "base":
            return [self.src / BASE]
        if kind == "bench":
            return [self.root / "bench", self.root / "fixtures"]
        if kind == "fixtures":
            return [self.root / "fixtures"]
        return []

    def check_public(self, path, number, name, kind, layer):
        parts = name.split("/")
        if name == EVERYONE:
            return
        target = parts[1] if len(parts) > 2 else "deform"
        generated = GENERATED_EXPORT.fullmatch(name)
        if not generated and not (self.include / name).is_file():
            self.refuse(path, number, f'includes "{name}", which is no public header')
            return
        if target == "deform":
            if kind != "bench" and kind != "fixtures":
                self.refuse(path, number, f'includes "{name}": the whole library is for its users, not its layers')
            return
        if target not in LAYERS:
            self.refuse(path, number, f'includes "{name}" of "{target}", which is not a layer')
            return
        if generated and kind in ("public", "private") and target != layer:
            self.refuse(path, number, f'includes "{name}", another layer\'s export macros')
            return
        allowed = self.uses(kind, layer)
        if target not in allowed:
            who = layer if kind in ("public", "private") else kind
            others = ", ".join(sorted(allowed - {layer})) or "no other layer"
            self.refuse(path, number, f'includes "{name}": {who} does not use {target} (it uses {others}; '
                        "docs/architecture.md)")

    def check_private(self, path, number, name, kind, layer):
        if kind in ("public", "umbrella"):
            self.refuse(path, number, f'public header includes "{name}", which is not a public header '
                        '(public headers include only "deform/..." headers)')
            return
        found = None
        for folder in [path.parent] + self.private_folders(kind, layer):
            candidate = (folder / name).resolve()
            if candidate.is_file():
                found = candidate
                break
        if found is None:
            elsewhere = sorted(str(p.relative_to(self.root)) for p in self.src.glob(f"*/{name}") if p.is_file())
            elsewhere += [str(p.relative_to(self.root)) for p in [self.src / name, self.root / name] if p.is_file()]
            where = f" (it is {', '.join(elsewhere)}, behind a wall)" if elsewhere else ""
            self.refuse(path, number, f'includes "{name}", which is neither beside it nor on its private include '
                        f"path{where}")
            return
        if not found.is_relative_to(self.root):
            self.refuse(path, number, f'includes "{name}", outside the source tree')
            return
        found_kind, found_layer = self.owner(found)
        if (found_kind, found_layer) == (kind, layer):
            return
        if found_kind == "base" and kind in ("private", "base"):
            return
        if kind == "bench" and found_kind == "fixtures":
            return
        what = {"private": f"a private header of {found_layer}", "base": "a header of the base",
                "tests": "a test's header", "public": "a public header by a relative path"}.get(found_kind,
                                                                                              "a header outside it")
        self.refuse(path, number, f'includes "{name}", {what} ({found.relative_to(self.root)})')

    def check_file(self, path):
        kind, layer = self.owner(path)
        if path.parent == self.src:
            self.refuse(path, 1, "a source outside every layer's folder (libdeform/src/<layer>/ or the base)")
            return
        if kind in ("public", "private") and layer not in LAYERS:
            self.refuse(path, 1, f'"{layer}" is not a layer: add it to LAYERS in {pathlib.Path(__file__).name} '
                        "and docs/architecture.md")
            return
        text = path.read_text(encoding="utf-8", errors="replace")
        for number, line in enumerate(text.splitlines(), 1):
            match = INCLUDE.match(line)
            if not match:
                continue
            bracket, name = match.groups()
            if name.startswith("deform/"):
                self.check_public(path, number, name, kind, layer)
            elif bracket == '"':
                self.check_private(path, number, name, kind, layer)

    def check_links(self):
        """LAYERS against each layer's CMakeLists.txt, and the table's own order."""
        for index, (layer, used) in enumerate(LAYERS.items()):
            earlier = list(LAYERS)[:index]
            for other in used:
                if other not in earlier:
                    self.problems.append(f"LAYERS: {layer} uses {other}, which is not above it in the table")
            lists = self.src / layer / "CMakeLists.txt"
            if not lists.is_file():
                self.problems.append(f"{lists.relative_to(self.root)}: missing (LAYERS names {layer})")
                continue
            text = re.sub(r"#[^\n]*", "", lists.read_text(encoding="utf-8"))
            linked = set()
            for call in re.finditer(rf"target_link_libraries\(\s*deform_{layer}\s([^)]*)\)", text):
                linked |= {name for name in re.findall(r"\bdeform_([a-z_]+)", call.group(1)) if name in LAYERS}
            if linked != set(used):
                self.problems.append(
                    f"{lists.relative_to(self.root)}: deform_{layer} links {', '.join(sorted(linked)) or 'no layer'}"
                    f", but LAYERS says it uses {', '.join(sorted(used)) or 'no layer'}")

    def run(self):
        self.check_links()
        for folder in sorted(p for p in self.src.iterdir() if p.is_dir()):
            if folder.name != BASE and folder.name not in LAYERS:
                self.problems.append(f"libdeform/src/{folder.name}: not a layer (LAYERS) and not the base")
        for folder in [self.include, self.src, self.root / "bench", self.root / "fixtures"]:
            if not folder.is_dir():
                continue
            for path in sorted(folder.rglob("*")):
                if path.suffix in SOURCE_SUFFIXES and path.is_file():
                    self.check_file(path)
        return self.problems


def main(argv):
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    problems = Walls(argv[1]).run()
    for problem in problems:
        print(problem)
    if problems:
        print(f"{len(problems)} include(s) across a wall (docs/architecture.md, \"Walls\")")
        return 1
    print("include walls: every include stays within its layer's walls")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
