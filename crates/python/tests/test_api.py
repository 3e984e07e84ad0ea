"""The public surface: every native function is reachable, documented and stubbed."""

import ast
import pathlib
import subprocess
import sys

import sepg
from sepg import _native, bounds

STUB = pathlib.Path(sepg.__file__).with_name("_native.pyi")


def test_every_native_item_has_a_docstring_and_a_stub():
    stubbed = {
        node.name
        for node in ast.parse(STUB.read_text()).body
        if isinstance(node, (ast.FunctionDef, ast.ClassDef))
    }
    public = {name for name in dir(_native) if not name.startswith("_")}
    assert public == stubbed
    for name in public:
        assert (getattr(_native, name).__doc__ or "").strip(), name


def test_bounds_exports_every_bound_function():
    prefixes = ("constants_", "pirotta_", "papini_", "batch_size_", "v_update_", "w_update_",
                "surrogate_", "high_probability_", "greedy_", "rigorous_", "budget_", "exploring_",
                "certified_")
    native = {n for n in dir(_native) if n.startswith(prefixes)}
    assert native <= set(bounds.__all__)
    # 43 functions of the closed forms, 5 more of the rigorous module (K_W, K_MU, the sound
    # c and its v-steps), the exploring w-step, and 14 of the certified module.
    assert len(native) == 43 + 5 + 1 + 14
    classes = {"Budget", "Certified", "Enclosure", "ExploringBound", "HighProbabilityBound", "Interval",
               "Quadratic", "StepOutcome"}
    assert classes <= set(bounds.__all__)
    for name in sepg.__all__:
        assert hasattr(sepg, name), name


def test_import_sepg_imports_neither_typing_nor_json_nor_numpy():
    # What `import sepg.runs` adds to a bare interpreter: the run path of the built-in
    # environments pays for no module it does not use (docs/PYTHON.md, "Speed").
    code = "import sys; b = set(sys.modules); import sepg.runs; print(*sorted(set(sys.modules) - b))"
    added = set(subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                               text=True).stdout.split())
    assert {"sepg", "sepg._native", "sepg.bounds", "sepg.errors", "sepg.runs"} <= added
    heavy = {"typing", "json", "re", "enum", "numpy", "pandas", "dataclasses", "gymnasium"}
    assert not heavy & added, heavy & added
