"""Evaluation: statistics, env/agent selection, env arguments, reports (on the fake env)."""

from __future__ import annotations

import csv
import json
import math

import pytest

from tests import cli_fakes
from tests.cli_fakes import BOX_ID, DISCRETE_ID, MAX_EPISODE_STEPS, SENSE_TIME_S
from sonar_gym.train import UsageError
from sonar_gym.train.evaluation import (
    EpisodeRecord,
    evaluate_agents,
    make_env,
    parse_env_args,
    resolve_agent_names,
    resolve_env_ids,
    summarize,
    t_confidence_interval,
)
from sonar_gym.train.report import (
    plot_results,
    results_to_dict,
    short_agent_label,
    summary_table,
    write_csv,
    write_json,
)

# Student-t quantiles from a printed table (e.g. NIST/SEMATECH e-Handbook, Table 1.3.6.7.2).
T_0975_DF4 = 2.776445
T_0975_DF1 = 12.706205
T_095_DF4 = 2.131847


def record(
    seed: int,
    reward: float = 0.0,
    position_error_m: float | None = 0.0,
    heading_error_rad: float | None = 0.0,
    sensing_time_s: float | None = 1.0,
    status: str = "ok",
) -> EpisodeRecord:
    return EpisodeRecord(
        seed, reward, position_error_m, heading_error_rad, sensing_time_s, status, steps=1
    )


# --------------------------------------------------------------------------------------------
# statistics


def test_t_interval_matches_hand_computation_for_five_values():
    interval = t_confidence_interval([1.0, 2.0, 3.0, 4.0, 5.0])
    # mean 3, sample variance 2.5, standard error sqrt(2.5 / 5)
    assert interval.mean == pytest.approx(3.0)
    assert interval.half_width == pytest.approx(T_0975_DF4 * math.sqrt(0.5), rel=1e-6)
    assert interval.low == pytest.approx(3.0 - 1.963243, abs=1e-5)
    assert interval.high == pytest.approx(3.0 + 1.963243, abs=1e-5)
    assert interval.n == 5


def test_t_interval_for_two_values_uses_one_degree_of_freedom():
    interval = t_confidence_interval([2.0, 4.0])
    # s = sqrt(2), standard error = 1
    assert interval.half_width == pytest.approx(T_0975_DF1, rel=1e-6)


def test_t_interval_at_ninety_percent_is_narrower():
    interval = t_confidence_interval([1.0, 2.0, 3.0, 4.0, 5.0], confidence=0.90)
    assert interval.half_width == pytest.approx(T_095_DF4 * math.sqrt(0.5), rel=1e-6)


def test_t_interval_of_one_value_has_no_width():
    interval = t_confidence_interval([7.5])
    assert interval.mean == 7.5 and interval.half_width is None and interval.low is None


def test_t_interval_rejects_empty_values_and_bad_confidence():
    with pytest.raises(ValueError, match="at least one"):
        t_confidence_interval([])
    with pytest.raises(ValueError, match="confidence"):
        t_confidence_interval([1.0, 2.0], confidence=1.5)


def test_summary_percentiles_use_successful_episodes_only():
    successes = [
        record(i, position_error_m=0.01 * (i + 1), heading_error_rad=0.1 * (i + 1))
        for i in range(10)
    ]
    failures = [
        record(10 + i, position_error_m=9.0, heading_error_rad=3.0, status="no_pair")
        for i in range(5)
    ]
    summary = summarize(successes + failures)
    assert summary.episodes == 15
    assert summary.successes == 10
    assert summary.success_rate == pytest.approx(10 / 15)
    # 0.01..0.10: median halfway between 0.05 and 0.06; p95 at rank 0.95 * 9 = 8.55
    assert summary.position_error_median_m == pytest.approx(0.055)
    assert summary.position_error_p95_m == pytest.approx(0.09 + 0.55 * 0.01)
    assert summary.heading_error_median_rad == pytest.approx(0.55)
    assert summary.heading_error_p95_rad == pytest.approx(0.955)


def test_summary_sensing_time_and_reward_cover_every_episode():
    records = [
        record(0, reward=-1.0, sensing_time_s=2.0),
        record(1, reward=-3.0, sensing_time_s=4.0, status="no_pair"),
        record(2, reward=-2.0, sensing_time_s=None),
    ]
    summary = summarize(records)
    assert summary.sensing_time_mean_s == pytest.approx(3.0)
    assert summary.reward.mean == pytest.approx(-2.0)
    assert summary.reward.half_width == pytest.approx(4.302653 / math.sqrt(3), rel=1e-6)


def test_summary_without_successes_has_no_error_statistics():
    summary = summarize([record(0, status="no_pair"), record(1, status="collinear")])
    assert summary.success_rate == 0.0
    assert summary.position_error_median_m is None
    assert summary.heading_error_p95_rad is None
    table = summary_table("X", [])  # an empty table still renders
    assert table.row_count == 0


def test_summary_ignores_missing_heading_errors():
    summary = summarize([record(0, heading_error_rad=None), record(1, heading_error_rad=None)])
    assert summary.heading_error_median_rad is None
    assert summary.position_error_median_m == 0.0


# --------------------------------------------------------------------------------------------
# selection


def test_all_expands_to_every_id_of_the_namespace_in_registration_order():
    ids = resolve_env_ids("all", namespace=cli_fakes.FAKE_NAMESPACE)
    assert ids == [DISCRETE_ID, BOX_ID, cli_fakes.MULTI_DISCRETE_ID]


def test_unknown_env_id_lists_the_registered_ones():
    with pytest.raises(UsageError) as error:
        resolve_env_ids("SonarGym/Nope-v0")
    assert "SonarGym/Nope-v0" in str(error.value)
    assert "'all'" in str(error.value)
    with pytest.raises(UsageError, match="did you mean 'CliFake/Locate-v0'"):
        resolve_env_ids("CliFake/Locate-v1", namespace=cli_fakes.FAKE_NAMESPACE)


def test_default_agents_are_every_registered_agent_of_the_env():
    plan = resolve_agent_names([DISCRETE_ID])
    assert {"scripted", "coin", "patient", "random"} <= set(plan[DISCRETE_ID])


def test_unknown_agent_lists_the_agents_of_the_env():
    with pytest.raises(UsageError) as error:
        resolve_agent_names([DISCRETE_ID], ["wizard"])
    message = str(error.value)
    assert "wizard" in message and "scripted" in message and "coin" in message


def test_missing_model_file_is_reported(tmp_path):
    with pytest.raises(UsageError, match="no saved model"):
        resolve_agent_names([DISCRETE_ID], [str(tmp_path / "missing.zip")])


def test_env_args_parse_numbers_bools_none_lists_and_strings():
    parsed = parse_env_args(
        ["a=3", "b=0.25", "c=true", "d=False", "e=none", "f=[1, 2]", "g=beom_cho_lab", "h=-1e-3"]
    )
    assert parsed == {
        "a": 3,
        "b": 0.25,
        "c": True,
        "d": False,
        "e": None,
        "f": [1, 2],
        "g": "beom_cho_lab",
        "h": -1e-3,
    }
    assert isinstance(parsed["a"], int)


@pytest.mark.parametrize("item", ["novalue", "=3", "two words=1", "x=[1,"])
def test_malformed_env_args_are_refused(item):
    with pytest.raises(UsageError):
        parse_env_args([item])


def test_repeated_env_arg_is_refused():
    with pytest.raises(UsageError, match="twice"):
        parse_env_args(["a=1", "a=2"])


def test_unknown_env_argument_names_the_allowed_ones():
    with pytest.raises(UsageError) as error:
        make_env(DISCRETE_ID, {"nois_std_m": 0.1})
    assert "nois_std_m" in str(error.value) and "noise_std_m" in str(error.value)


def test_env_argument_value_rejected_by_the_env_keeps_its_message():
    with pytest.raises(UsageError, match="noise_std_m.*must lie in"):
        make_env(DISCRETE_ID, {"noise_std_m": 3.0})


# --------------------------------------------------------------------------------------------
# running


def test_same_seed_gives_identical_records():
    first = evaluate_agents(DISCRETE_ID, ["scripted", "coin", "random"], episodes=6, seed=11)
    second = evaluate_agents(DISCRETE_ID, ["scripted", "coin", "random"], episodes=6, seed=11)
    assert [r.records for r in first] == [r.records for r in second]
    third = evaluate_agents(DISCRETE_ID, ["scripted"], episodes=6, seed=12)
    assert third[0].records != first[0].records


def test_episodes_are_paired_across_agents_and_action_encodings():
    results = evaluate_agents([DISCRETE_ID, BOX_ID], ["scripted", "coin"], episodes=5, seed=3)
    assert [(r.env_id, r.agent) for r in results] == [
        (DISCRETE_ID, "scripted"),
        (DISCRETE_ID, "coin"),
        (BOX_ID, "scripted"),
        (BOX_ID, "coin"),
    ]
    for result in results:
        assert [r.seed for r in result.records] == [3, 4, 5, 6, 7]
    # the same task and seeds behind two action encodings: the same episodes
    assert results[0].records == results[2].records
    assert results[1].records == results[3].records


def test_records_carry_the_end_of_episode_info():
    result = evaluate_agents(DISCRETE_ID, ["scripted"], episodes=4, seed=0)[0]
    for episode in result.records:
        assert episode.status == "ok"
        assert episode.steps == cli_fakes.SCRIPTED_MEASUREMENTS + 1
        expected_time_s = cli_fakes.SCRIPTED_MEASUREMENTS * SENSE_TIME_S
        assert episode.sensing_time_s == pytest.approx(expected_time_s)
        assert episode.heading_error_rad == pytest.approx(0.5 * episode.position_error_m)
        expected_reward = (
            -cli_fakes.SENSING_COST * SENSE_TIME_S * cli_fakes.SCRIPTED_MEASUREMENTS
            - episode.position_error_m
        )
        assert episode.reward == pytest.approx(expected_reward)
    assert result.summary == summarize(result.records)


def test_episode_cut_by_the_time_limit_is_marked_truncated():
    result = evaluate_agents(DISCRETE_ID, ["patient"], episodes=2, seed=0)[0]
    for episode in result.records:
        assert episode.status == "truncated"
        assert episode.steps == MAX_EPISODE_STEPS
        assert episode.position_error_m is None
    assert result.summary.success_rate == 0.0


def test_env_kwargs_reach_the_env():
    result = evaluate_agents(
        DISCRETE_ID,
        ["scripted"],
        episodes=3,
        seed=0,
        env_kwargs={"report_heading": False, "noise_std_m": 0.0},
    )[0]
    for episode in result.records:
        assert episode.heading_error_rad is None
        assert episode.position_error_m == pytest.approx(0.0, abs=1e-12)


def test_evaluate_agents_checks_the_selection_before_running():
    with pytest.raises(UsageError):
        evaluate_agents(DISCRETE_ID, ["scripted", "wizard"], episodes=1)
    with pytest.raises(UsageError):
        evaluate_agents(DISCRETE_ID, ["scripted"], episodes=1, env_kwargs={"bogus": 1})
    with pytest.raises(ValueError, match="episodes"):
        evaluate_agents(DISCRETE_ID, ["scripted"], episodes=0)


def test_progress_callback_sees_every_episode():
    seen = []
    evaluate_agents(
        DISCRETE_ID,
        ["scripted", "coin"],
        episodes=3,
        seed=0,
        on_episode=lambda env_id, agent, rec: seen.append((env_id, agent, rec.seed)),
    )
    assert seen == [(DISCRETE_ID, a, s) for a in ("scripted", "coin") for s in (0, 1, 2)]


# --------------------------------------------------------------------------------------------
# reports


def test_json_report_holds_summaries_and_every_episode(tmp_path):
    results = evaluate_agents(DISCRETE_ID, ["scripted", "coin"], episodes=5, seed=0)
    path = write_json(results, tmp_path / "out" / "e.json", meta={"seed": 0})
    data = json.loads(path.read_text())
    assert data["meta"] == {"seed": 0}
    assert [(r["env_id"], r["agent"]) for r in data["results"]] == [
        (DISCRETE_ID, "scripted"),
        (DISCRETE_ID, "coin"),
    ]
    scripted = data["results"][0]
    assert len(scripted["episodes"]) == 5
    assert scripted["episodes"][0]["seed"] == 0
    assert set(scripted["episodes"][0]) == {
        "seed",
        "reward",
        "position_error_m",
        "heading_error_rad",
        "sensing_time_s",
        "status",
        "steps",
    }
    summary = results[0].summary
    assert scripted["summary"]["success_rate"] == summary.success_rate
    assert scripted["summary"]["position_error_median_m"] == summary.position_error_median_m
    assert scripted["summary"]["reward_mean"] == pytest.approx(summary.reward.mean)
    assert scripted["summary"]["reward_ci_low"] == pytest.approx(
        summary.reward.mean - summary.reward.half_width
    )
    assert results_to_dict(results)["results"][1]["agent"] == "coin"


def test_csv_report_has_one_row_per_episode_and_blank_missing_values(tmp_path):
    results = evaluate_agents(DISCRETE_ID, ["scripted", "patient"], episodes=3, seed=0)
    path = write_csv(results, tmp_path / "e.csv")
    with path.open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 6
    assert rows[0]["agent"] == "scripted" and rows[0]["status"] == "ok"
    assert float(rows[0]["position_error_m"]) == results[0].records[0].position_error_m
    assert rows[3]["agent"] == "patient" and rows[3]["position_error_m"] == ""
    assert rows[3]["steps"] == str(MAX_EPISODE_STEPS)


def test_saved_models_get_short_labels_in_plots():
    assert short_agent_label("/tmp/x/runs/beacon-ppo-0/model.zip") == "beacon-ppo-0/model.zip"
    assert short_agent_label("paper") == "paper"


def test_plot_is_a_png_with_one_row_per_env(tmp_path):
    results = evaluate_agents([DISCRETE_ID, BOX_ID], ["scripted", "patient"], episodes=2, seed=0)
    path = plot_results(results, tmp_path / "plots" / "e.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_output_folder_name_is_made_of_the_arguments() -> None:
    from sonar_gym.train.evaluation import MAX_FOLDER_NAME, output_folder_name

    assert output_folder_name(["SonarGym/BeaconScan-v0"], None, 50, 0) == (
        "BeaconScan-v0_all-agents_50ep_seed0"
    )
    assert output_folder_name(["all"], ["paper", "random"], 10, 3, {"max_steps": 20}) == (
        "all_paper+random_10ep_seed3_max_steps=20"
    )
    # a saved model by its run directory and file; no path separators reach the name
    assert output_folder_name(["all"], ["runs/bs-ppo-0/model.zip"], 5, 0) == (
        "all_bs-ppo-0.model_5ep_seed0"
    )
    long = output_folder_name(["all"], ["a" * 300], 5, 0)
    assert len(long) == MAX_FOLDER_NAME
    assert long != output_folder_name(["all"], ["a" * 301], 5, 0)  # the hash tells them apart


def test_plot_panels_leave_out_the_heading_error_where_no_agent_has_one():
    from sonar_gym.train.report import evaluation_panels

    with_heading = evaluate_agents(DISCRETE_ID, ["scripted"], episodes=2, seed=0)
    without = evaluate_agents(
        DISCRETE_ID, ["scripted"], episodes=2, seed=0, env_kwargs={"report_heading": False}
    )
    assert evaluation_panels(with_heading) == [
        "E_xy [cm]",
        "E_θ [deg]",
        "mean sensing time [s]",
        "episode reward (mean, 95% CI)",
    ]
    assert evaluation_panels(without) == [
        "E_xy [cm]",
        "mean sensing time [s]",
        "episode reward (mean, 95% CI)",
    ]


def test_plot_marks_thin_samples_and_draws_the_reward_interval():
    from sonar_gym.train.report import THIN_SAMPLE, evaluation_figure, sample_note

    assert sample_note(3) == "n=3" and sample_note(THIN_SAMPLE) == "" and sample_note(0) == ""
    results = evaluate_agents(DISCRETE_ID, ["scripted", "coin"], episodes=4, seed=0)
    figure = evaluation_figure(results)
    successes = [result.summary.successes for result in results]
    assert any(0 < n < THIN_SAMPLE for n in successes)
    for column in (0, 1):  # E_xy and E_θ
        labels = [label.get_text() for label in figure.axes[column].get_xticklabels()]
        for label, n in zip(labels, successes, strict=True):
            assert (f"(n={n})" in label) == (0 < n < THIN_SAMPLE)
    sensing_labels = [label.get_text() for label in figure.axes[2].get_xticklabels()]
    assert not any("n=" in label for label in sensing_labels)
    reward_axis = figure.axes[3]
    assert reward_axis.get_ylabel() == "episode reward (mean, 95% CI)"
    # the error bar spans the Student-t interval of the first agent
    (bars,) = [c for c in reward_axis.containers]
    segments = bars.lines[2][0].get_segments()
    low, high = segments[0][0][1], segments[0][1][1]
    interval = results[0].summary.reward
    assert low == pytest.approx(interval.low) and high == pytest.approx(interval.high)
