#!/usr/bin/env python3
"""The include-walls check must be able to fail: include_walls.py run on small trees written here, one lawful and one
per kind of crossing, each with one bad line; the lawful tree must pass and every other must be refused, naming the
file and line of its bad include.

    include_walls_test.py   (exit status 0 when every case behaves, 1 otherwise)
"""
import pathlib
import subprocess
import sys
import tempfile

CHECK = pathlib.Path(__file__).with_name("include_walls.py")
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, str(CHECK.parent))
from include_walls import LAYERS  # noqa: E402  (the fixture's CMakeLists.txt link exactly what the table says)

# The lawful tree: every layer's CMakeLists.txt, and each kind of include the walls allow.
LAWFUL = {
    "libdeform/include/deform/runtime/skeleton.hpp": '#include "deform/runtime/export.hpp"\n',
    "libdeform/include/deform/offline/rig.hpp": '#include "deform/runtime/skeleton.hpp"\n#include <vector>\n',
    "libdeform/include/deform/io/obj.hpp": '#include "deform/offline/rig.hpp"\n',
    "libdeform/include/deform/deform.hpp": '#include "deform/io/obj.hpp"\n#include "deform/version.hpp"\n',
    "libdeform/src/base/finite.hpp": '#include "deform/runtime/skeleton.hpp"\n',
    "libdeform/src/runtime/kernel.hpp": '#include "finite.hpp"\n',
    "libdeform/src/runtime/simd/kernel_avx2.cpp": '#include "kernel.hpp"\n#include "simd_kernel.hpp"\n',
    "libdeform/src/runtime/simd/simd_kernel.hpp": '#include "../kernel.hpp"\n',
    "libdeform/src/runtime/skeleton.cpp": '#include "deform/runtime/skeleton.hpp"\n#include "simd/simd_kernel.hpp"\n',
    "libdeform/src/offline/rig.cpp": '#include "deform/offline/rig.hpp"\n#include "finite.hpp"\n',
    "libdeform/src/io/obj.cpp": '#include "deform/io/obj.hpp"\n#include <nlohmann/json.hpp>\n',
    "fixtures/rigs.hpp": '#include "deform/runtime/skeleton.hpp"\n',
    "bench/fixtures.hpp": '#include "rigs.hpp"\n',
    "bench/ik_bench.cpp": '#include "deform/deform.hpp"\n#include "fixtures.hpp"\n',
    "tests/runtime/rig.hpp": "\n",
}
for layer, used in LAYERS.items():
    links = " ".join(f"deform_{other}" for other in used)
    LAWFUL[f"libdeform/src/{layer}/CMakeLists.txt"] = (
        f"deform_add_library({layer} a.cpp)\n" + (f"target_link_libraries(deform_{layer} PUBLIC {links})\n" if used
                                                  else ""))

# Each crossing: (what, file, its text, the text the refusal must contain).
CROSSINGS = [
    ("a layer includes a higher layer's public header", "libdeform/src/offline/topology.cpp",
     '#include "deform/io/obj.hpp"\n', "libdeform/src/offline/topology.cpp:1"),
    ("a public header includes a layer it does not use", "libdeform/include/deform/runtime/mesh.hpp",
     '\n#include "deform/offline/rig.hpp"\n', "libdeform/include/deform/runtime/mesh.hpp:2"),
    ("a layer includes another layer's private header by its old path", "libdeform/src/offline/binding.cpp",
     '#include "runtime/kernel.hpp"\n', "libdeform/src/runtime/kernel.hpp, behind a wall"),
    ("a layer includes another layer's private header by a relative path", "libdeform/src/io/sk.cpp",
     '#include "../runtime/kernel.hpp"\n', "a private header of runtime"),
    ("a public header includes the base", "libdeform/include/deform/offline/weights.hpp",
     '#include "deform/runtime/skeleton.hpp"\n#include "../../../src/base/finite.hpp"\n',
     "libdeform/include/deform/offline/weights.hpp:2"),
    ("a public header includes a private header", "libdeform/include/deform/runtime/lattice.hpp",
     '#include "kernel.hpp"\n', "public header includes"),
    ("the base includes a layer above runtime", "libdeform/src/base/paths.hpp",
     '#include "deform/io/obj.hpp"\n', "libdeform/src/base/paths.hpp:1"),
    ("a layer includes another layer's export macros", "libdeform/src/offline/export_use.cpp",
     '#include "deform/runtime/export.hpp"\n', "another layer's export macros"),
    ("a benchmark includes a test's header", "bench/normals_bench.cpp",
     '#include "../tests/runtime/rig.hpp"\n', "a test's header"),
    ("a benchmark includes a private header", "bench/skin_bench.cpp",
     '#include "../libdeform/src/runtime/kernel.hpp"\n', "a private header of runtime"),
    ("a fixture includes a test's header", "fixtures/normals.hpp",
     '#include "../tests/runtime/rig.hpp"\n', "fixtures/normals.hpp:1"),
    ("a layer's CMakeLists.txt links a layer the table does not give it", "libdeform/src/offline/CMakeLists.txt",
     "target_link_libraries(deform_offline PUBLIC deform_runtime deform_io)\n", "LAYERS says it uses runtime"),
    ("a folder that is no layer", "libdeform/src/physics/solver.cpp", "\n", "libdeform/src/physics: not a layer"),
    ("a source in no layer's folder", "libdeform/src/helpers.hpp", "\n", "libdeform/src/helpers.hpp:1"),
]


def write(root, files):
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")


def run(root):
    result = subprocess.run([sys.executable, str(CHECK), str(root)], capture_output=True, text=True)
    return result.returncode, result.stdout + result.stderr


def main():
    failures = 0
    with tempfile.TemporaryDirectory() as temp:
        lawful = pathlib.Path(temp) / "lawful"
        write(lawful, LAWFUL)
        status, output = run(lawful)
        if status != 0:
            print(f"FAIL: the lawful tree was refused (status {status}):\n{output}")
            failures += 1
        for index, (what, name, text, expected) in enumerate(CROSSINGS):
            root = pathlib.Path(temp) / f"crossing{index}"
            write(root, {**LAWFUL, name: text})
            status, output = run(root)
            if status != 1 or expected not in output:
                print(f"FAIL: {what}: status {status} (1 expected), output without '{expected}':\n{output}")
                failures += 1
            else:
                print(f"ok: {what} is refused")
    print(f"{len(CROSSINGS) + 1 - failures} of {len(CROSSINGS) + 1} cases behave")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
