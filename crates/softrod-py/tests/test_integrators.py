"""The one list of integrators: softrod.INTEGRATORS comes from Rust
(softrod-integrate's Integrator::ALL); the type stubs, which cannot be
generated at import, must name the same integrators in the same order."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import softrod

STUB = Path(softrod.__file__).with_name("_softrod.pyi")


def stub_integrator_names() -> tuple[str, ...]:
    """The strings of ``_IntegratorName = Literal[...]`` in the stub."""
    tree = ast.parse(STUB.read_text())
    for node in tree.body:
        if (isinstance(node, ast.Assign)
                and [t.id for t in node.targets if isinstance(t, ast.Name)] == ["_IntegratorName"]):
            value = node.value
            assert isinstance(value, ast.Subscript) and ast.unparse(value.value) == "Literal"
            items = value.slice.elts if isinstance(value.slice, ast.Tuple) else [value.slice]
            return tuple(ast.literal_eval(item) for item in items)
    raise AssertionError(f"no _IntegratorName in {STUB}")


def test_the_stub_names_the_integrators_of_the_rust_list():
    assert stub_integrator_names() == softrod.INTEGRATORS


def test_the_list_is_the_scene_names():
    # The scene format's names (docs/scene-format-extensions.md), each
    # accepted by Settings and reported back unchanged.
    assert set(softrod.INTEGRATORS) == {
        "rk4", "dopri5", "rosenbrock", "generalized-alpha", "esdirk", "esdirk5", "radau5"}
    for name in softrod.INTEGRATORS:
        assert softrod.Settings(integrator=name).integrator == name
    with pytest.raises(softrod.InputError, match="unknown integrator"):
        softrod.Settings(integrator="euler")
