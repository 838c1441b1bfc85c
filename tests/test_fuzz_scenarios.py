"""Fuzzed scenario files: a ``ScenarioError`` naming the file, or a world pymunk can build.

Three sources of files: structured scenarios with random (often wrong) fields written as TOML
or JSON, built-in scenarios with a few characters changed (mostly malformed TOML), and
arbitrary text. A file that loads must build a :class:`~sonar_gym.world.World` whose geometry
answers queries without raising.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import event, given
from hypothesis import strategies as st

from sonar_gym.scenario import BUILTIN_DIR, ScenarioError, builtin_names, load_scenario
from sonar_gym.world import World
from tests.fuzzing import EDGE_NUMBERS, fuzz_settings


def toml_value(value: Any) -> str:
    """``value`` written as a TOML value (floats as TOML spells nan and inf)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(type(value))


def toml_text(data: dict[str, Any]) -> str:
    """A scenario mapping as TOML: tables as ``[name]``, lists of tables as ``[[name]]``."""
    lines: list[str] = []
    for key, value in data.items():
        if isinstance(value, dict):
            lines.append(f"[{key}]")
            lines += [f"{json.dumps(k)} = {toml_value(v)}" for k, v in value.items()]
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for item in value:
                lines.append(f"[[{key}]]")
                lines += [f"{json.dumps(k)} = {toml_value(v)}" for k, v in item.items()]
        else:
            lines.insert(0, f"{json.dumps(key)} = {toml_value(value)}")
    return "\n".join(lines) + "\n"


bad_number = st.one_of(
    st.sampled_from(EDGE_NUMBERS), st.floats(allow_nan=True, allow_infinity=True)
)
anything = st.one_of(
    st.text(max_size=4), st.booleans(), bad_number, st.lists(bad_number, max_size=4)
)


def mostly(valid: st.SearchStrategy[Any], wrong: st.SearchStrategy[Any]) -> st.SearchStrategy:
    """``valid`` about nine times in ten, else ``wrong``."""
    return st.one_of(*([valid] * 9), wrong)


coordinate = mostly(st.floats(-3.0, 3.0), st.one_of(bad_number, st.integers(-5, 5)))
length = mostly(st.floats(0.01, 1.0), bad_number)
vec2 = mostly(st.lists(coordinate, min_size=2, max_size=2), anything)
vec3 = mostly(st.tuples(coordinate, coordinate, st.floats(0.0, 3.0)).map(list), anything)
room = mostly(
    st.tuples(
        st.floats(-4.0, -1.0), st.floats(-4.0, -1.0), st.floats(1.0, 4.0), st.floats(1.0, 4.0)
    ).map(lambda r: {"min": [r[0], r[1]], "max": [r[2], r[3]]}),
    st.fixed_dictionaries({"min": vec2, "max": vec2}),
)
mapped = mostly(st.booleans(), anything)


def table(required: dict[str, Any], optional: dict[str, Any]) -> st.SearchStrategy[dict]:
    return st.fixed_dictionaries(required, optional=optional)


scenario_data = st.fixed_dictionaries(
    {"room": room},
    optional={
        "meta": table(
            {}, {"name": st.text(max_size=8), "description": mostly(st.text(), anything)}
        ),
        "walls": st.lists(table({"a": vec2, "b": vec2}, {"mapped": mapped}), max_size=3),
        "boxes": st.lists(
            table(
                {"center": vec2, "size": mostly(st.lists(length, min_size=2, max_size=2), vec2)},
                {"angle_deg": mostly(st.floats(-180.0, 180.0), bad_number), "mapped": mapped},
            ),
            max_size=3,
        ),
        "cylinders": st.lists(
            table(
                {"center": vec2, "radius": mostly(st.floats(0.01, 0.2), bad_number)},
                {"role": st.sampled_from(["clutter", "small_beacon", "large_beacon", "x"])},
            ),
            max_size=3,
        ),
        "emitters": st.lists(
            table({"name": st.sampled_from(["A", "B", "", "C"]), "position": vec3}, {}),
            max_size=3,
        ),
        "robot": table(
            {},
            {
                "radius": mostly(st.floats(0.05, 0.4), bad_number),
                "sensor_offset": mostly(
                    st.lists(st.floats(-0.1, 0.1), min_size=2, max_size=2), vec2
                ),
                "wheel_base": length,
                "sensor_height": length,
            },
        ),
        "sensor": table(
            {}, {"preset": mostly(st.sampled_from(["polaroid-6500", "srf04"]), anything)}
        ),
        "reflector": table({}, {"distance": mostly(st.floats(0.1, 1.0), bad_number)}),
        "extra": anything,
    },
)


def check_loads_or_names_the_file(path: Path) -> None:
    try:
        scenario = load_scenario(path)
    except ScenarioError as error:
        assert str(path) in str(error), str(error)
        event("clean ScenarioError")
        return
    world = World(scenario)
    (x0, y0), (x1, y1) = scenario.bounds
    centre = ((x0 + x1) / 2.0, (y0 + y1) / 2.0)
    world.is_free(centre)
    world.line_of_sight((x0, y0), (x1, y1))
    event("loaded and built a world")


@fuzz_settings(300)
@given(data=scenario_data, as_json=st.booleans())
def test_generated_scenarios_load_or_name_the_file(
    tmp_path_factory: pytest.TempPathFactory, data: dict[str, Any], as_json: bool
) -> None:
    folder = tmp_path_factory.mktemp("generated", numbered=True)
    if as_json:
        path = folder / "world.json"
        path.write_text(json.dumps(data), encoding="utf-8")
    else:
        path = folder / "world.toml"
        path.write_text(toml_text(data), encoding="utf-8")
    check_loads_or_names_the_file(path)


BUILTIN_TEXTS = [
    (BUILTIN_DIR / f"{name}.toml").read_text(encoding="utf-8") for name in builtin_names()
]


@st.composite
def mutated_builtin(draw: st.DrawFn) -> str:
    """A built-in scenario with one to four characters deleted, replaced or inserted."""
    text = draw(st.sampled_from(BUILTIN_TEXTS))
    for _ in range(draw(st.integers(1, 4))):
        at = draw(st.integers(0, len(text) - 1))
        kind = draw(st.sampled_from(["delete", "replace", "insert"]))
        char = draw(st.sampled_from(list("[]{}=\"'.,-0123456789e\n #x")))
        if kind == "delete":
            text = text[:at] + text[at + 1 :]
        elif kind == "replace":
            text = text[:at] + char + text[at + 1 :]
        else:
            text = text[:at] + char + text[at:]
    return text


@fuzz_settings(300)
@given(text=st.one_of(mutated_builtin(), st.text(max_size=200)))
def test_malformed_toml_is_a_scenario_error_naming_the_file(
    tmp_path_factory: pytest.TempPathFactory, text: str
) -> None:
    path = tmp_path_factory.mktemp("mutated", numbered=True) / "world.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    check_loads_or_names_the_file(path)
