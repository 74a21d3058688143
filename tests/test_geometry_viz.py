"""The chapter-01 widget callback (motionlab.viz.rotations) and the geometry benchmark."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import torch  # noqa: E402

from motionlab.bench import geometry as bench  # noqa: E402
from motionlab.viz.rotations import plot_interpolation, show_interpolation  # noqa: E402


def test_show_interpolation_draws_both_paths_and_slerp_angle_is_linear():
    fig = show_interpolation(0, 0, 0, 120, 30, -45, w=0.25)
    try:
        sphere_ax, angle_ax = fig.axes[:2]
        labels = [line.get_label() for line in angle_ax.get_lines()]
        assert labels[:2] == ["slerp", "nlerp"]
        slerp, nlerp = angle_ax.get_lines()[:2]
        w, slerp_angle, nlerp_angle = slerp.get_xdata(), slerp.get_ydata(), nlerp.get_ydata()
        # slerp: angle from q0 grows linearly in the weight w; nlerp: same endpoints, different speed
        np.testing.assert_allclose(slerp_angle, slerp_angle[-1] * w, atol=1e-9)
        np.testing.assert_allclose(nlerp_angle[[0, -1]], slerp_angle[[0, -1]], atol=1e-9)
        assert np.abs(nlerp_angle - slerp_angle).max() > 1.0  # degrees
        assert len(sphere_ax.get_lines()) >= 2
    finally:
        plt.close(fig)


def test_plot_interpolation_checks_its_arguments():
    q = torch.tensor([1.0, 0, 0, 0])
    with pytest.raises(ValueError, match=r"plot_interpolation: w must be in \[0, 1\], got 1.5"):
        plot_interpolation(q, q, 1.5)
    with pytest.raises(ValueError, match=r"plot_interpolation: q1 must be 1-dimensional, got shape \(2, 4\)"):
        plot_interpolation(q, torch.ones(2, 4), 0.5)
    with pytest.raises(ValueError, match=r"plot_interpolation: q1 must have shape \(\.\.\., 4\), got \(3,\)"):
        plot_interpolation(q, torch.ones(3), 0.5)
    with pytest.raises(TypeError, match="plot_interpolation: q0 must be a torch.Tensor, got list"):
        plot_interpolation([1.0, 0.0, 0.0, 0.0], q, 0.5)


def test_benchmark_reports_throughput_bandwidth_and_copy_reference():
    result = bench.kernel_speed(n_items=2000, repeats=2, include_compiled=False)  # make bench compiles
    for kernel in ("quat_to_matrix", "quat_geodesic", "matrix_geodesic"):
        assert result[f"{kernel}.items_per_s"] > 0
        assert result[f"{kernel}.bytes_per_s"] > 0
        assert result[f"{kernel}.copy_bytes_per_s"] > 0
        assert 0 < result[f"{kernel}.fraction_of_copy_bandwidth"]
    assert result["n_items"] == 2000 and result["threads"] == 1
    assert result["pipeline.eager.items_per_s"] > 0 and "pipeline.compiled.items_per_s" not in result
