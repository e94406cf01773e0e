"""Counterfactual robustness benchmark: suites of language perturbations, paired evaluation of a
policy on base and perturbed episodes, reports, local and Ray backends; scene-quality reports.

    from morphosim_gym.bench import load_suite, run_sweep
    result = run_sweep(load_suite("smoke"), ["oracle", "random"], "out/smoke")

Command line: `morphosim bench SUITE --policy oracle --out DIR`, `morphosim quality PROMPTS --out report.md`.
"""

from .episode import EpisodeKey, EpisodeRunner
from .runner import SweepResult, plan_episodes, run_sweep
from .suite import CameraShift, Perturbation, Suite, SuiteError, builtin_suite_names, load_suite

__all__ = ["Suite", "Perturbation", "CameraShift", "SuiteError", "load_suite", "builtin_suite_names", "run_sweep",
           "SweepResult", "plan_episodes", "EpisodeKey", "EpisodeRunner"]
