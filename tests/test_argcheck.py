"""drakedeburr.argcheck: the checks every command runs on its arguments before any work."""

from __future__ import annotations

import pytest

from drakedeburr.argcheck import separate_outputs
from drakedeburr.errors import InputError


def test_an_output_that_is_an_input_is_refused_naming_both(tmp_path):
    plan = tmp_path / "plan.json"
    plan.write_text("{}")
    with pytest.raises(InputError, match="outputs never replace inputs") as e:
        separate_outputs({"--json": plan}, inputs={"the plan": plan})
    assert str(plan) in str(e.value) and "--json" in str(e.value)


def test_an_output_through_a_link_to_an_input_is_refused(tmp_path):
    plan = tmp_path / "plan.json"
    plan.write_text("{}")
    (tmp_path / "alias.json").symlink_to(plan)
    with pytest.raises(InputError, match="outputs never replace inputs"):
        separate_outputs({"--json": tmp_path / "alias.json"}, inputs={"the plan": plan})


def test_two_outputs_naming_one_file_are_refused(tmp_path):
    out = tmp_path / "report"
    with pytest.raises(InputError, match="name the same file"):
        separate_outputs({"--json": out, "--html": out})


def test_an_output_inside_an_input_folder_is_refused(tmp_path):
    folder = tmp_path / "plan"
    folder.mkdir()
    with pytest.raises(InputError):
        separate_outputs({"--html": folder / "arrays.npz"}, input_folders={"the plan": folder})


def test_separate_outputs_pass_and_unset_options_are_skipped(tmp_path):
    plan = tmp_path / "plan" / "plan.json"
    separate_outputs({"--json": tmp_path / "r.json", "--html": None},
                     inputs={"the plan": plan}, input_folders={"the plan": plan.parent})
