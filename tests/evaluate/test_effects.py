"""Paired effect sizes, the headline against walkers only, the verdict in words and the report's sections."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.evaluate.found import found_effects, found_leads, summarise_found
from curiosity_cli.evaluate.headline import headline, paired_effects, with_adjusted, with_uncertainty
from curiosity_cli.evaluate.report import verdict, write_report
from curiosity_cli.evaluate.stage import Evaluation
from curiosity_cli.evaluate.statistics import paired_difference, paired_tests, summarise, summarise_classes
from curiosity_cli.explore.weights import CEILINGS

WALKERS = ("random-walk", "stochastic-coverage", "word-perplexity", "topic-perplexity", "lawnmower")
# topic perplexity's lead over stochastic coverage, the next best, per restart: all positive, no ties (a tie makes
# scipy's Wilcoxon a slow permutation test)
LEAD = np.array([0.10, 0.12, 0.08, 0.11, 0.09, 0.105, 0.13, 0.07, 0.115, 0.095])


@pytest.mark.parametrize("seed, n", [(0, 2), (1, 5), (2, 20)])
def test_the_paired_ci_is_scipys(seed, n):
    rng = np.random.default_rng(seed)
    a = rng.normal(0.5, 0.1, n)
    b = a - rng.normal(0.03, 0.05, n)
    mean, low, high = paired_difference(a, b)
    reference = stats.ttest_rel(a, b).confidence_interval(0.95)
    assert mean == pytest.approx(np.mean(a - b), rel=1e-12)
    assert (low, high) == pytest.approx((reference.low, reference.high), rel=1e-12)
    reference = stats.ttest_rel(a, b).confidence_interval(0.9)
    assert paired_difference(a, b, 0.9)[1:] == pytest.approx((reference.low, reference.high), rel=1e-12)


def test_the_paired_ci_on_known_data():
    # differences 1, 2, 3: mean 2, sd 1, t(0.975, 2) = 4.302653: 2 ± 4.302653 / sqrt(3)
    mean, low, high = paired_difference(np.array([2.0, 4.0, 6.0]), np.array([1.0, 2.0, 3.0]))
    assert (mean, low, high) == pytest.approx((2.0, 2 - 4.302653 / np.sqrt(3), 2 + 4.302653 / np.sqrt(3)), rel=1e-6)
    # one pair: no interval; every difference the same: an interval of width 0, as scipy's
    assert np.isnan(paired_difference(np.array([1.0]), np.array([0.0]))[1])
    assert paired_difference(np.array([1.0, 2.0, 3.0]), np.array([0.0, 1.0, 2.0])) == (1.0, 1.0, 1.0)


def synthetic_mi() -> pd.DataFrame:
    """Three maps, five walkers and two ceilings, 10 restarts at 40 and 80 steps.

    ``win``: human labels, topic perplexity ahead of everyone by LEAD or more;
    ``loss``: human labels, topic perplexity below stochastic coverage and word perplexity in every restart;
    ``unlabelled``: no human labels, topic perplexity ahead on MI against Z_b.
    """
    rng = np.random.default_rng(7)
    centres = {"random-walk": 0.2, "stochastic-coverage": 0.4, "word-perplexity": 0.3, "lawnmower": 0.35}
    ceilings = {CEILINGS[0]: 0.9, CEILINGS[-1]: 0.8} if len(CEILINGS) > 1 else {CEILINGS[0]: 0.9}
    rows = []
    for dataset in ("win", "loss", "unlabelled"):
        for length in (40, 80):
            base = 0.4 + 0.01 * rng.standard_normal(10)
            for weight in (*WALKERS, *ceilings):
                for restart in range(10):
                    if weight == "topic-perplexity":
                        mi = base[restart] + LEAD[restart] if dataset != "loss" else 0.25 + 0.01 * np.sin(restart)
                    elif weight == "stochastic-coverage":
                        mi = base[restart]
                    elif weight == "word-perplexity" and dataset == "loss":
                        mi = 0.30 + 0.01 * rng.standard_normal()
                    else:
                        mi = centres.get(weight, ceilings.get(weight)) - 0.1 + 0.01 * rng.standard_normal()
                    if weight in ceilings:
                        mi = ceilings[weight] + 0.001 * restart
                    human = dataset != "unlabelled"
                    rows.append({
                        "dataset": dataset, "weight_function": weight, "restart": restart, "path_length": length,
                        "mi_human": mi if human else np.nan, "mi_batch": mi, "nmi_human": np.nan, "nmi_batch": np.nan,
                        "classes_found": (restart % 3 + 2) if human else np.nan, "classes": 6 if human else np.nan,
                        "mean_recall": (0.5 + 0.01 * restart) if human else np.nan, "seed": str(restart),
                        "replicate": 0,
                    })
    return pd.DataFrame(rows)


def tables():
    mi = synthetic_mi()
    summary, tests = summarise(mi), paired_tests(mi)
    effects = paired_effects(mi, tests)
    top = headline(summary, tests, {"win": "Montreal1", "loss": "SouthBellairs", "unlabelled": "Montreal2"}, effects)
    return mi, summary, tests, effects, with_adjusted(with_uncertainty(top, mi))


@pytest.mark.slow
def test_effects_are_topic_perplexity_minus_each_walker_paired_by_restart_and_leave_ceilings_out():
    mi, _, tests, effects, _ = tables()
    assert not effects["other"].isin(CEILINGS).any() and not tests[["a", "b"]].isin(CEILINGS).any().any()
    assert set(effects["other"]) == set(WALKERS) - {"topic-perplexity"}
    assert len(effects) == 3 * 2 * 4 + 2 * 2 * 4  # human: 2 maps, batch: 3 maps; 2 lengths; 4 others
    row = effects[(effects.dataset == "win") & (effects.path_length == 80) & (effects.against == "human")
                  & (effects.other == "stochastic-coverage")].iloc[0]
    block = mi[(mi.dataset == "win") & (mi.path_length == 80)].pivot(index="restart", columns="weight_function", values="mi_human")
    reference = stats.ttest_rel(block["topic-perplexity"], block["stochastic-coverage"]).confidence_interval(0.95)
    assert row["mean_difference"] == pytest.approx(LEAD.mean(), rel=1e-9) and row["n"] == 10
    assert (row["ci_low"], row["ci_high"]) == pytest.approx((reference.low, reference.high), rel=1e-9)
    # every one of 10 pairs favours topic perplexity: the exact two-sided Wilcoxon p is 2 / 2**10
    assert row["p_value"] == pytest.approx(2 / 2**10)


@pytest.mark.slow
def test_the_headline_compares_walkers_only_and_falls_back_to_batch_labels():
    *_, top = tables()
    top = top.set_index("dataset")
    # the ceilings have the highest MI but are never the next best
    assert top.loc["win", "next_best"] == "stochastic-coverage" and bool(top.loc["win", "beats_all"])
    assert top.loc["win", "not_beaten"] == ""
    assert top.loc["win", "best_ceiling"] == CEILINGS[0]
    assert top.loc["win", "ceiling_share"] == pytest.approx(top.loc["win", "topic_perplexity"] / top.loc["win", "ceiling_mi"])
    assert top.loc["loss", "next_best"] == "stochastic-coverage" and not top.loc["loss", "beats_all"]
    assert top.loc["unlabelled", "against"] == "batch" and top.loc["win", "against"] == "human"


def test_the_verdict_of_a_clear_win():
    _, _, _, effects, top = tables()
    row = top.set_index("dataset").loc["win"].to_dict() | {"dataset": "win"}
    low, high = row["ci_low"], row["ci_high"]
    assert 0 < low < high
    assert row["ratio_ci_low"] < row["ratio"] < row["ratio_ci_high"] and 1 < row["detectable_ratio"] < row["ratio"]
    # the walkers that do not differ, permuted: the observed ratio is above their median and their p is small
    assert row["null_low"] < row["null_median"] < row["ratio"] and row["null_p"] < 0.05
    assert row["null_no_rw_low"] < row["null_no_rw_median"] < row["ratio"] and row["null_no_rw_p"] < 0.05
    # the lead's p over the experiment's two maps with human labels: win's and loss's (1: its mean is not the highest)
    assert row["p_each"] == pytest.approx(each_p := max(effects.query(
        "dataset == 'win' and path_length == 80 and against == 'human'")["p_value"]))
    assert row["p_each_holm"] == pytest.approx(min(1.0, 2 * each_p))
    each = effects[(effects.dataset == "win") & (effects.path_length == 80) & (effects.against == "human")]
    alone = ", ".join(
        f"{r.other} {r.ratio:.2f} (95 % CI {r.ratio_ci_low:.2f} to {r.ratio_ci_high:.2f}), p = {r.p_value:.3f}"
        for r in each.itertuples()
    )
    assert verdict(row, effects) == (
        f"win: topic perplexity beats every other walker at 80 steps (p = {each_p:.3f} against each, Holm p = "
        f"{2 * each_p:.3f} over the experiment's maps); against each alone, MI ratio {alone}: 0.10 bits "
        f"above stochastic-coverage, the next "
        f"best (95 % CI +{low:.2f} to +{high:.2f}), p = 0.002; ratio {row['ratio']:.2f} (95 % CI "
        f"{row['ratio_ci_low']:.2f} to {row['ratio_ci_high']:.2f}; walkers that do not differ (the random walk left "
        f"out) give {row['null_no_rw_median']:.2f}, 95 % {row['null_no_rw_low']:.2f} to {row['null_no_rw_high']:.2f}: "
        f"null p = {row['null_no_rw_p']:.2f}) "
        f"against the paper's 1.51 on "
        f"Montreal1. It reaches {100 * row['ceiling_share']:.0f} % of the better ceiling's MI ({CEILINGS[0]}, "
        f"{row['ceiling_mi']:.2f} bits). With 10 pairs it could detect a lead of "
        f"{100 * (row['detectable_ratio'] - 1):.0f} % or more at 80 % power; a 10 % lead would need "
        f"{row['pairs_for_lead']} pairs."
    )


@pytest.mark.slow
def test_the_verdict_of_a_clear_loss():
    row = {
        "dataset": "zurich-zh17", "path_length": 80, "against": "human", "topic_perplexity": 0.38, "next_best": "word-perplexity",
        "next_best_mi": 0.40, "ratio": 0.95, "mean_difference": -0.02, "ci_low": -0.05, "ci_high": 0.01,
        "p_value": 0.48, "pairs": 20, "beats_all": False, "not_beaten": "word-perplexity;lawnmower",
        "best_ceiling": "", "ceiling_mi": np.nan, "ceiling_share": np.nan, "paper_map": "Montreal1", "paper_ratio": 1.51,
    }
    assert verdict(row) == (
        "zurich-zh17: topic perplexity does not beat every walker at 80 steps: 0.02 bits below word-perplexity "
        "(95 % CI \u22120.05 to +0.01), p = 0.48; not clearly ahead of lawnmower either; ratio 0.95 against the "
        "paper's 1.51 on Montreal1."
    )
    *_, top = tables()
    loss = top.set_index("dataset").loc["loss"].to_dict() | {"dataset": "loss"}
    assert verdict(loss).startswith("loss: topic perplexity does not beat every walker at 80 steps: ")
    assert "bits below stochastic-coverage (95 % CI \u2212" in verdict(loss) and "p = 0.002" in verdict(loss)


def test_the_verdict_of_a_map_that_no_walker_can_gather_mi_on_says_why_the_ratio_is_undefined():
    # human labels of one class (a hostile user's map): every walker's MI is 0, the ratio 0 / 0
    row = {
        "dataset": "one-class", "path_length": 80, "against": "human", "topic_perplexity": 0.0, "next_best": "random-walk",
        "next_best_mi": 0.0, "ratio": np.nan, "mean_difference": 0.0, "ci_low": 0.0, "ci_high": 0.0,
        "p_value": np.nan, "pairs": 2, "beats_all": False, "not_beaten": "random-walk",
        "best_ceiling": "", "ceiling_mi": np.nan, "ceiling_share": np.nan, "paper_map": "", "paper_ratio": np.nan,
    }
    text = verdict(row)
    assert "ratio nan" not in text
    assert "; ratio undefined: random-walk's MI is 0 bits (a map whose human labels hold one class, or whose words " in text


@pytest.mark.slow
def test_the_verdict_of_a_map_without_human_labels():
    *_, top = tables()
    row = top.set_index("dataset").loc["unlabelled"].to_dict() | {"dataset": "unlabelled"}
    text = verdict(row)
    assert text.startswith(
        "unlabelled (MI against Z_b: the map has no human labels): topic perplexity beats every other walker at 80 "
        f"steps (p = {row['p_each']:.3f} against each, Holm p = {row['p_each_holm']:.3f} over the experiment's maps): "
        "0.10 bits above stochastic-coverage, the next best (95 % CI +"
    )
    assert row["p_each_holm"] == row["p_each"], "the only map measured against Z_b: a family of one"
    assert f"ratio {row['ratio']:.2f} (95 % CI " in text
    assert "against the paper's 1.20 on Montreal2 (against human labels there)." in text


def test_a_lead_that_is_not_significant_is_not_a_win():
    row = {
        "dataset": "m", "path_length": 80, "against": "human", "topic_perplexity": 0.42, "next_best": "lawnmower", "next_best_mi": 0.40,
        "ratio": 1.05, "mean_difference": 0.02, "ci_low": -0.01, "ci_high": 0.05, "p_value": 0.31, "pairs": 10,
        "beats_all": False, "not_beaten": "lawnmower", "best_ceiling": "", "ceiling_mi": np.nan,
        "ceiling_share": np.nan, "paper_map": np.nan, "paper_ratio": np.nan,
    }
    assert verdict(row) == (
        "m: topic perplexity leads every other walker at 80 steps, but not clearly: 0.02 bits above lawnmower, the "
        "next best (95 % CI \u22120.01 to +0.05), p = 0.31; ratio 1.05 (no paper map to compare with)."
    )


@pytest.mark.slow
def test_the_report_leads_with_the_verdict_and_has_every_section(tmp_path):
    mi, summary, tests, effects, top = tables()
    mi = mi[mi.dataset != "loss"]  # so that one map's verdict is read at its longest path below 80 steps
    mi = pd.concat([mi, synthetic_mi().query("dataset == 'loss' and path_length == 40")])
    summary, tests = summarise(mi), paired_tests(mi)
    effects = paired_effects(mi, tests)
    top = with_adjusted(with_uncertainty(headline(summary, tests, {"win": "Montreal1"}, effects), mi))
    found = found_effects(mi)
    evaluation = Evaluation(
        mi, summary, tests, top, ["a note"], None, effects=effects, classes_summary=summarise_classes(mi),
        found_summary=summarise_found(mi), found_effects=found, found_leads=found_leads(found),
    )
    config = load_config(CONFIG_DIR / "quick.yaml")
    config = dataclasses.replace(
        config, explore=dataclasses.replace(config.explore, weight_functions=(*WALKERS, *CEILINGS))
    )
    path = write_report(tmp_path, config, evaluation, [], [], {"total": 3.0}, {"git_commit": "abc", "curiosity": "1"})
    report = path.read_text()
    lines = report.splitlines()
    assert lines[0].startswith("# Curiosity-driven exploration") and lines[2].startswith("Reproduction of")
    assert f"5 walkers and {len(CEILINGS)} ceilings" in lines[2]
    assert lines[4:6] == ["## Verdict", ""] and lines[6].startswith("- win: ")  # the answer first
    bullets = [line for line in lines if line.startswith("- ")]
    assert bullets[0].startswith("- win: topic perplexity beats every other walker at 80 steps")
    assert bullets[1].startswith(
        "- loss: topic perplexity does not beat every walker at 40 steps (its longest path; the paper reads 80); "
        "against each alone, MI ratio lawnmower "
    )
    assert "| loss | 40 | human | " in report and "| win | 80 | human | " in report  # the headline table says which
    assert bullets[2].startswith("- unlabelled (MI against Z_b")
    sections = [line for line in lines if line.startswith("## ")]
    assert sections == [
        "## Verdict", "## Headline", "## Mutual information (bits, mean ± 95 % CI half-width)", "## Label convergence",
        "## Paired effect sizes",
        "## What each walker found at 80 steps", "## Significance", "## Left out", "## Figures", "## Time", "## Config",
    ]
    assert f"| win | {CEILINGS[0]} (ceiling) |" in report and "Ceilings (" in report
    assert "| win | human | lawnmower | " in report
    assert "at least 10 % of the cell's pixels" in report and "one topic a class" in report
    # classes found 2, 3, 4, 2, 3, 4, ... over 10 restarts: mean 2.9, CI half-width t(0.975, 9) * 0.876 / sqrt(10);
    # mean recall 0.5 + 0.01 restart: 0.545; the same for every walker, so no difference and no lead
    assert "| | classes found (of 6) | mean recall |" in report
    assert "| topic-perplexity | 2.90 ± 0.63 | 0.545 ± 0.022 |" in report
    assert "| topic-perplexity − lawnmower | +0.00 [+0.00, +0.00], p = 1.00 | +0.000 [+0.000, +0.000], p = 1.00 |" in report
    assert "| leads each | no (p = 1.00; Holm: p = 1.00) | no (p = 1.00; Holm: p = 1.00) |" in report
    assert "Not in `mi.csv` (made before they existed; evaluate again): AMI, time to first find, MI where the path went, MI where the path did not go, held-out log-likelihood, held-out log-likelihood where the path did not go." in report


def test_too_few_pairs_for_any_test_to_reach_p_005_are_said_plainly():
    from curiosity_cli.evaluate.report import _significance
    from curiosity_cli.evaluate.statistics import smallest_wilcoxon_p

    for pairs in range(1, 9):  # every difference of one sign: scipy's exact p is the smallest there is
        assert stats.wilcoxon(np.arange(1.0, pairs + 1)).pvalue == pytest.approx(smallest_wilcoxon_p(pairs))
    mi = synthetic_mi()
    mi = mi[(mi.restart < 2) & (mi.dataset == "win")]  # 2 pairs: the smallest p is 0.5
    summary, tests = summarise(mi), paired_tests(mi)
    top = with_uncertainty(headline(summary, tests, {"win": "Montreal1"}, paired_effects(mi, tests)), mi)
    row = top.iloc[0].to_dict()
    assert row["pairs"] == 2 and row["p_value"] == pytest.approx(0.5)
    assert "p = 0.50 (with 2 pairs no paired test can reach p < 0.05: the smallest p is 0.5);" in verdict(row)
    text = " ".join(_significance(tests))
    assert "no pair differs at p < 0.05, but with 2 pairs or fewer no test could: the smallest p of 2 pairs is 0.5" in text
    assert "as the paper reports" not in text
    could = tests.assign(n=10, p_value=0.3)  # 10 pairs could reach it, and did not
    assert "no pair differs at p < 0.05, as the paper reports." in " ".join(_significance(could))


def test_a_map_whose_paths_are_all_longer_than_80_steps_has_no_verdict():
    from curiosity_cli.evaluate.report import _no_verdict
    from curiosity_cli.evaluate.headline import headline_length

    assert headline_length([10, 40, 160]) == 40 and headline_length([80, 160]) == 80 and headline_length([160]) is None
    mi = synthetic_mi().query("dataset == 'win' and path_length == 80").assign(path_length=160)
    summary, tests = summarise(mi), paired_tests(mi)
    assert headline(summary, tests, {}).empty
    assert _no_verdict(summary, "win") == "win: no verdict: no checkpoint of 80 steps or fewer."
