"""The names and defaults of the package are those of the Rust crates: the extension module
hands them over from one table, and they are the names of Table 4.1 and the defaults of the
thesis's protocol (Sec 5.1)."""

import inspect

import pytest

import sepg
from sepg import _native

# Table 4.1's requirements in the table's order, and the algorithms as `sepg run --algo`
# names them (docs/PYTHON.md, docs/REPRODUCTION.md).
TABLE_4_1 = ("mi", "lb1", "lb2", "lv", "zv", "sim")
ALGORITHMS = ("sepg-mi", "sepg-lb1", "sepg-lb2", "sepg-lv", "sepg-zv", "sepg-sim",
              "sepg-naive-w", "gpomdp-const", "gpomdp-adam", "adastep")


def test_the_name_tuples_are_the_extension_modules():
    assert _native._REQUIREMENTS == TABLE_4_1
    assert _native._ALGORITHMS == ALGORITHMS
    assert sepg._REQUIREMENTS is _native._REQUIREMENTS
    model = pytest.importorskip("sepg.model")
    assert model._REQUIREMENTS is _native._REQUIREMENTS


def test_every_algorithm_and_requirement_name_is_accepted_and_no_other():
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 2.0)
    steps = {"gpomdp-const": {"alpha": 0.1}, "gpomdp-adam": {"lr": 0.1}}
    for name in _native._ALGORITHMS:
        sepg.Trainer(name, k, 1, 1, lambda req: None, **steps.get(name, {}))
    for requirement in _native._REQUIREMENTS:
        sepg.Trainer("sepg-naive-w", k, 1, 1, lambda req: None, requirement=requirement)
    listed = ", ".join(ALGORITHMS[:-1]) + " or " + ALGORITHMS[-1]
    with pytest.raises(sepg.InvalidInputError) as e:
        sepg.Trainer("sepg-xx", k, 1, 1, lambda req: None)
    assert str(e.value) == f'unknown algorithm "sepg-xx": expected {listed}'
    with pytest.raises(sepg.InvalidInputError) as e:
        sepg.Trainer("sepg-naive-w", k, 1, 1, lambda req: None, requirement="lb3")
    assert str(e.value) == 'unknown requirement "lb3": expected mi, lb1, lb2, lv, zv or sim'


def test_the_defaults_of_the_python_faces_are_the_protocols():
    # Sec 5.1: delta = 0.2, N = 100, seed 0, B0 = 0, nu = 0.5; SEPG-ZV with the tight
    # constants, as `sepg run` resolves an empty configuration.
    protocol = {"delta": 0.2, "n_trajectories": 100, "seed": 0, "initial_budget": 0.0,
                "nu": 0.5, "requirement": "zv", "constants": "tight", "algorithm": "sepg-zv"}
    assert _native._DEFAULT_DELTA == protocol["delta"]
    assert _native._DEFAULT_N_TRAJECTORIES == protocol["n_trajectories"]
    assert _native._DEFAULT_REQUIREMENT == protocol["requirement"]
    assert _native._DEFAULT_CONSTANTS == protocol["constants"]
    pytest.importorskip("gymnasium")
    from sepg import gym as sg
    from sepg.model import SEPG

    for f in (sg.train, sg.GymRun.__init__, SEPG.__init__):
        params = inspect.signature(f).parameters
        for name, value in protocol.items():
            if name in params:
                assert params[name].default == value, (f, name)
