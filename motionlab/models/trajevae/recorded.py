"""Recorded results of runs too long for chapter 07's time budget, with their provenance.

:data:`SCHEDULE_CHECK_RECORDED` holds :func:`~motionlab.models.trajevae.experiment.schedule_check` in the full
profile (``ExperimentConfig.full()``'s model and data) for 400 and 1,600 steps, with either reconstruction
term; the chapter shows them next to its own run's numbers. Rerun the function to refresh them.
"""

from __future__ import annotations

#: Where and how the records below were made.
SCHEDULE_CHECK_PROVENANCE = (
    "schedule_check's measurements in the full profile (ExperimentConfig.full(): 48 test "
    "windows, 50 samples), recorded on 2026-12-02 with the model and loss of commit 42a1141 on "
    "a shared two-core machine. "
)

#: One dict per run: ``reconstruction``, ``steps`` and what ``schedule_check`` returned.
SCHEDULE_CHECK_RECORDED: tuple[dict[str, float | int | str], ...] = (
    {
        "reconstruction": "sum",
        "steps": 400,
        "follow": 0.6638,
        "follow_ci95": 0.1874,
        "decode_prior_k0": 2.0531,
        "decode_posterior_k0": 0.0362,
        "sigma_p_k0": 0.924,
        "sigma_q_k0": 0.316,
        "decode_prior_k2": 0.8919,
        "decode_posterior_k2": 0.0469,
        "sigma_p_k2": 0.99,
        "sigma_q_k2": 0.317,
        "decode_prior_k4": 0.2045,
        "decode_posterior_k4": 0.0596,
        "sigma_p_k4": 0.666,
        "sigma_q_k4": 0.317,
        "apd_k0": 18.401,
        "apd_k0_ci95": 1.275,
        "apd_k4": 21.118,
        "apd_k4_ci95": 6.221,
        "train_seconds": 214.2,
    },
    {
        "reconstruction": "mean",
        "steps": 400,
        "follow": 0.4841,
        "follow_ci95": 0.1124,
        "decode_prior_k0": 1.441,
        "decode_posterior_k0": 0.0401,
        "sigma_p_k0": 1.132,
        "sigma_q_k0": 1.054,
        "decode_prior_k2": 0.3067,
        "decode_posterior_k2": 0.0455,
        "sigma_p_k2": 1.113,
        "sigma_q_k2": 1.056,
        "decode_prior_k4": 0.1284,
        "decode_posterior_k4": 0.0446,
        "sigma_p_k4": 1.074,
        "sigma_q_k4": 1.057,
        "apd_k0": 14.645,
        "apd_k0_ci95": 3.487,
        "apd_k4": 14.108,
        "apd_k4_ci95": 3.497,
        "train_seconds": 209.5,
    },
    {
        "reconstruction": "sum",
        "steps": 1600,
        "follow": 0.3751,
        "follow_ci95": 0.1119,
        "decode_prior_k0": 2.3465,
        "decode_posterior_k0": 0.0214,
        "sigma_p_k0": 0.726,
        "sigma_q_k0": 0.126,
        "decode_prior_k2": 0.5026,
        "decode_posterior_k2": 0.0233,
        "sigma_p_k2": 0.714,
        "sigma_q_k2": 0.126,
        "decode_prior_k4": 0.0999,
        "decode_posterior_k4": 0.024,
        "sigma_p_k4": 0.303,
        "sigma_q_k4": 0.126,
        "apd_k0": 14.595,
        "apd_k0_ci95": 1.97,
        "apd_k4": 7.721,
        "apd_k4_ci95": 2.707,
        "train_seconds": 1192.1,
    },
    {
        "reconstruction": "mean",
        "steps": 1600,
        "follow": 0.3116,
        "follow_ci95": 0.0631,
        "decode_prior_k0": 0.9153,
        "decode_posterior_k0": 0.0252,
        "sigma_p_k0": 0.728,
        "sigma_q_k0": 0.641,
        "decode_prior_k2": 0.1919,
        "decode_posterior_k2": 0.0256,
        "sigma_p_k2": 0.677,
        "sigma_q_k2": 0.642,
        "decode_prior_k4": 0.0406,
        "decode_posterior_k4": 0.0253,
        "sigma_p_k4": 0.648,
        "sigma_q_k4": 0.642,
        "apd_k0": 22.436,
        "apd_k0_ci95": 8.101,
        "apd_k4": 7.311,
        "apd_k4_ci95": 1.444,
        "train_seconds": 732.4,
    },
)
