"""The Python examples of README.md and docs/PYTHON.md run as printed."""

import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
FENCE = re.compile(r"^```python\n(.*?)^```", re.DOTALL | re.MULTILINE)


def blocks(name):
    return [(name, i, code) for i, code in enumerate(FENCE.findall((ROOT / name).read_text()))]


EXAMPLES = blocks("README.md") + blocks("docs/PYTHON.md")


def test_the_readme_has_its_three_examples():
    readme = [code for name, _, code in EXAMPLES if name == "README.md"]
    assert len(readme) == 3
    assert len(readme[0].strip().splitlines()) <= 12
    assert len(readme[1].strip().splitlines()) <= 22
    assert len(readme[2].strip().splitlines()) <= 12


@pytest.mark.parametrize("name,index,code", EXAMPLES, ids=[f"{n}-{i}" for n, i, _ in EXAMPLES])
def test_example_runs_as_printed(name, index, code, capsys):
    exec(compile(code, f"{name} example {index}", "exec"), {"__name__": "__example__"})
    assert capsys.readouterr().out
