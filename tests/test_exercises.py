"""The "your turn" exercises: every solution passes its checker, every skeleton in the chapters raises
NotImplementedError with a message (so the chapter goes on), and every checker names typical mistakes."""

from __future__ import annotations

import importlib.util
import json
import math
import re
from types import ModuleType

import numpy as np
import pytest
import torch

import motionlab.exercises as exercises
from motionlab import geometry as geo
from motionlab.course.chapters import numbered_notebooks
from motionlab.exercises.checking import CheckResult
from motionlab.models.gaussian import gaussian_kl
from motionlab.paths import REPO_ROOT

NOTEBOOKS = REPO_ROOT / "notebooks"


def solutions(chapter: str) -> ModuleType:
    path = next((NOTEBOOKS / "solutions").glob(f"{chapter}_*.py"))
    spec = importlib.util.spec_from_file_location(f"solutions_{chapter}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def your_turn_cells() -> list[tuple[str, str]]:
    """(chapter file name, cell source) of every cell tagged ``your-turn``, in chapters and appendices (an
    appendix's solutions live in its chapter's solutions file)."""
    cells = []
    for path in numbered_notebooks(NOTEBOOKS):
        for cell in json.loads(path.read_text())["cells"]:
            if "your-turn" in cell.get("metadata", {}).get("tags", []):
                cells.append((path.name, "".join(cell["source"])))
    return cells


CELLS = your_turn_cells()


def test_every_chapter_with_exercises_has_solutions_and_checkers() -> None:
    assert CELLS, "no your-turn cells found"
    for chapter, source in CELLS:
        names = re.findall(r"^def (my_\w+)\(", source, re.M)
        assert names, f"{chapter}: a your-turn cell without a my_ function"
        for name in names:
            checker = f"check_{name.removeprefix('my_')}"
            assert hasattr(exercises, checker), f"{chapter}: no motionlab.exercises.{checker} for {name}"
            assert f"{checker}({name})" in source, f"{chapter}: the cell does not call {checker}({name})"
            assert hasattr(solutions(chapter[:2]), name), f"{chapter}: no solution for {name}"


@pytest.mark.parametrize("chapter, source", CELLS, ids=[f"{c[:2]}-{i}" for i, (c, _) in enumerate(CELLS)])
def test_skeletons_raise_not_implemented_with_a_message_and_the_checker_says_not_done(
    chapter, source
) -> None:
    captured: dict[str, CheckResult] = {}
    namespace = {"torch": torch}
    for name in exercises.__all__:
        if name.startswith("check_"):
            checker = getattr(exercises, name)
            namespace[name] = lambda fn, checker=checker, name=name: captured.setdefault(name, checker(fn))
    exec(compile(source, chapter, "exec"), namespace)
    assert captured and all(result.status == "not done" for result in captured.values()), captured
    for key, fn in namespace.items():
        if key.startswith("my_"):
            with pytest.raises(NotImplementedError, match=r"\w+ \w+"):
                fn(*[torch.zeros(4)] * fn.__code__.co_argcount)


@pytest.mark.parametrize(
    "chapter, name",
    [
        ("01", "my_quat_mul"),
        ("01", "my_slerp"),
        ("02", "my_chain_positions"),
        ("02", "my_foot_skating"),
        ("03", "my_reparameterize"),
        ("03", "my_gaussian_kl"),
        ("03", "my_negative_elbo"),
        ("04", "my_subtree_reach"),
        ("04", "my_impact_weights"),
        ("04", "my_motion_cell_step"),
        ("05", "my_coupling_forward"),
        ("05", "my_coupling_inverse"),
        ("06", "my_sample_loop"),
        ("06", "my_keep_mask"),
        ("07", "my_dct_matrix"),
        ("07", "my_given_trajectories"),
        ("07", "my_prior_kl"),
        ("08", "my_contrastive_loss"),
        ("08", "my_covariance_prior"),
        ("11", "my_ancestral_step"),
    ],
)
def test_solutions_pass_their_checkers(chapter: str, name: str) -> None:
    checker = getattr(exercises, f"check_{name.removeprefix('my_')}")
    result = checker(getattr(solutions(chapter), name))
    assert result.passed, result


def _unbatched_mul(q1, q2):
    w1, x1, y1, z1 = q1[0], q1[1], q1[2], q1[3]
    w2, x2, y2, z2 = q2[0], q2[1], q2[2], q2[3]
    return torch.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2, w1 * y2, w1 * z2])


def _w_last_mul(q1, q2):  # the scipy (x, y, z, w) convention applied to w-first data
    roll = lambda q: torch.roll(q, -1, dims=-1)  # noqa: E731
    return torch.roll(geo.quat_mul(roll(q1), roll(q2)), 1, dims=-1)


def _numpy_mul(q1, q2):
    return torch.as_tensor(
        geo.quat_mul(torch.as_tensor(q1.detach().numpy()), torch.as_tensor(q2.detach().numpy()))
    )


@pytest.mark.parametrize(
    "wrong, says",
    [
        (lambda q1, q2: geo.quat_mul(q2, q1), "q2 ⊗ q1"),
        (lambda q1, q2: -geo.quat_mul(q1, q2), "wrong sign"),
        (_unbatched_mul, "shape"),
        (_w_last_mul, "w comes first"),
        (lambda q1, q2: geo.quat_mul(q1.reshape(-1, 4), q2.reshape(-1, 4)).reshape(q1.shape), "broadcast"),
        (lambda q1, q2: geo.quat_mul(q1[:1], q2[:1]).expand(q1.shape), "the first pair is right"),
        (_numpy_mul, "gradient"),
        (lambda q1, q2: geo.quat_mul(q1, q2).double(), "dtype"),
        (lambda q1, q2: geo.quat_mul(q1, q2).tolist(), "torch.Tensor"),
        (lambda q1, q2: q1.undefined_attribute, "AttributeError"),
    ],
)
def test_quat_mul_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_quat_mul(wrong)
    assert result.status == "wrong" and says in result.message, result


def _naive_slerp(q0, q1, w):
    w = torch.as_tensor(w, dtype=q0.dtype).unsqueeze(-1)
    q1 = torch.where((q0 * q1).sum(-1, keepdim=True) < 0, -q1, q1)
    omega = torch.acos((q0 * q1).sum(-1, keepdim=True).clamp(-1, 1))
    return (torch.sin((1 - w) * omega) * q0 + torch.sin(w * omega) * q1) / torch.sin(omega)


def _long_way_slerp(q0, q1, w):
    w = torch.as_tensor(w, dtype=q0.dtype).unsqueeze(-1)
    omega = torch.acos((q0 * q1).sum(-1, keepdim=True).clamp(-1, 1))
    return (torch.sin((1 - w) * omega) * q0 + torch.sin(w * omega) * q1) / torch.sin(omega)


def _lerp(q0, q1, w):
    w = torch.as_tensor(w, dtype=q0.dtype).unsqueeze(-1)
    return (1 - w) * q0 + w * q1


def _scalar_w_only(q0, q1, w):
    return geo.quat_slerp(q0, q1, float(w) if not isinstance(w, torch.Tensor) else float(w.flatten()[0]))


def _too_fast(q0, q1, w):
    return geo.quat_slerp(q0, q1, torch.as_tensor(w, dtype=q0.dtype) ** 2)


@pytest.mark.parametrize(
    "wrong, says",
    [
        (geo.quat_nlerp, "nlerp"),
        (_lerp, "unit sphere"),
        (_long_way_slerp, "shorter arc"),
        (_naive_slerp, "NaN"),
        (_scalar_w_only, "(9, 4)"),
        (_too_fast, "evenly"),
        (lambda q0, q1, w: q1, "at w = 0.0"),
    ],
)
def test_slerp_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_slerp(wrong)
    assert result.status == "wrong" and says in result.message, result


def _chain(rotations, root, offsets, own=False, reverse=False, skip_root=False, batched=True):
    positions, frame = [root], rotations[..., 0, :]
    if skip_root:
        positions = [torch.zeros_like(root)]
    for k in range(1, rotations.shape[-2]):
        if own:
            frame = geo.quat_mul(frame, rotations[..., k, :])
        positions.append(positions[-1] + geo.quat_apply(frame, offsets[k].expand_as(root)))
        if not own:
            frame = (
                geo.quat_mul(rotations[..., k, :], frame)
                if reverse
                else geo.quat_mul(frame, rotations[..., k, :])
            )
    return torch.stack(positions, dim=-2 if batched else 1)


@pytest.mark.parametrize(
    "wrong, says",
    [
        (lambda r, x, o: _chain(r, x, o, own=True), "its own joint's global rotation"),
        (lambda r, x, o: _chain(r, x, o, reverse=True), "wrong order"),
        (lambda r, x, o: _chain(r, x, o, skip_root=True), "root position"),
        (lambda r, x, o: _chain(r, x, o, batched=False), "leading dimensions"),
        (lambda r, x, o: _chain(r, x, o)[..., :2, :], "should give positions (5, 4, 3)"),
        (lambda r, x, o: torch.as_tensor(np.asarray(_chain(r.detach(), x, o))), "gradient"),
    ],
)
def test_chain_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_chain_positions(wrong)
    assert result.status == "wrong" and says in result.message, result


def test_a_result_displays_as_one_line() -> None:
    result = exercises.check_quat_mul(lambda q1, q2: geo.quat_mul(q2, q1))
    assert str(result).startswith("✗ quat_mul: ") and "\n" not in str(result)
    assert exercises.check_quat_mul(geo.quat_mul)._repr_markdown_().startswith("**✓")


def _draw(scale):
    return lambda mu, logvar, generator: (
        mu + scale(logvar) * torch.randn(mu.shape, generator=generator, dtype=mu.dtype)
    )


@pytest.mark.parametrize(
    "wrong, says",
    [
        (_draw(torch.exp), "exp(logvar) is the variance"),
        (_draw(lambda logvar: logvar.abs().sqrt()), "sigma = exp(logvar / 2)"),
        (_draw(torch.ones_like), "ignores logvar"),
        (
            lambda mu, logvar, generator: torch.normal(mu, torch.exp(0.5 * logvar), generator=generator),
            "torch.normal",
        ),
        (lambda mu, logvar, generator: mu + torch.exp(0.5 * logvar) * torch.randn_like(mu), "generator"),
        (lambda mu, logvar, generator: mu.detach() + 0 * logvar.detach(), "not sigma"),
    ],
)
def test_reparameterize_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_reparameterize(wrong)
    assert result.status == "wrong" and says in result.message, result


@pytest.mark.parametrize(
    "wrong, says",
    [
        (lambda mu, logvar: (0.5 * (mu**2 + logvar.exp() - 1 - logvar)).sum(-1), "summed over dimensions"),
        (lambda mu, logvar: -0.5 * (mu**2 + logvar.exp() - 1 - logvar), "sign is flipped"),
        (lambda mu, logvar: mu**2 + logvar.exp() - 1 - logvar, "factor 1/2"),
        (lambda mu, logvar: 0.5 * (mu**2 + logvar.exp() - logvar), "the -1"),
        (lambda mu, logvar: 0.5 * (mu**2 + logvar.exp() ** 2 - 1 - 2 * logvar), "already the variance"),
        (lambda mu, logvar: 0.5 * (mu + logvar.exp() - 1 - logvar), "1/2 (mu^2"),
    ],
)
def test_gaussian_kl_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_gaussian_kl(wrong)
    assert result.status == "wrong" and says in result.message, result


def _elbo(z_of=lambda mu, logvar, eps: mu + torch.exp(0.5 * logvar) * eps, recon_scale=0.5, kl_of=None):
    """A negative ELBO with one piece replaced: the draw, the reconstruction's factor or the KL."""

    def kl_right(mu, logvar):
        return 0.5 * (mu**2 + logvar.exp() - 1 - logvar).sum(-1)

    def fn(x, mu, logvar, eps, decode, obs_var):
        recon = recon_scale * ((x - decode(z_of(mu, logvar, eps))) ** 2).flatten(1).sum(-1) / obs_var
        return recon, (kl_of or kl_right)(mu, logvar)

    return fn


@pytest.mark.parametrize(
    "wrong, says",
    [
        (
            _elbo(kl_of=lambda mu, logvar: -0.5 * (mu**2 + logvar.exp() - 1 - logvar).sum(-1)),
            "sign is flipped",
        ),
        (_elbo(kl_of=lambda mu, logvar: (mu**2 + logvar.exp() - 1 - logvar).sum(-1)), "factor 1/2"),
        (_elbo(kl_of=lambda mu, logvar: 0.5 * (mu**2 + logvar.exp() - 1 - logvar)), "sum it over the latent"),
        (
            _elbo(kl_of=lambda mu, logvar: 0.5 * (mu**2 + logvar.exp() ** 2 - 1 - 2 * logvar).sum(-1)),
            "σ², not σ",
        ),
        (_elbo(kl_of=lambda mu, logvar: 0.5 * (mu**2 - 1).sum(-1)), "logvar is log σ²"),
        (_elbo(recon_scale=1.0), "factor 1/2"),
        (_elbo(z_of=lambda mu, logvar, eps: mu), "the decoder got mu"),
        (_elbo(z_of=lambda mu, logvar, eps: mu + logvar.exp() * eps), "the variance, as σ"),
        (_elbo(z_of=lambda mu, logvar, eps: mu + logvar * eps), "logvar as σ"),
        (_elbo(z_of=lambda mu, logvar, eps: mu + torch.exp(0.5 * logvar.detach()) * eps), "no gradient"),
        (lambda x, mu, logvar, eps, decode, obs_var: x.sum(), "tuple (recon, kl)"),
    ],
)
def test_negative_elbo_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_negative_elbo(wrong)
    assert result.status == "wrong" and says in result.message, result


def _cell_step(z_from="posterior", sigma=lambda logvar: torch.exp(0.5 * logvar), kl_to="prior", feed="word"):
    """A Motion Cell step with one piece replaced: where z comes from, its spread, the KL's prior or
    direction, the state the decoder reads, or the word the transition reads."""

    def fn(word, state, eps, prior, posterior, decode, transition):
        mu_p, logvar_p = prior(state)
        mu_q, logvar_q = posterior(word, state)
        mu, logvar = (mu_q, logvar_q) if z_from == "posterior" else (mu_p, logvar_p)
        z = mu + sigma(logvar) * eps
        kl = {
            "prior": lambda: gaussian_kl(mu_q, logvar_q, mu_p, logvar_p).sum(-1),
            "reversed": lambda: gaussian_kl(mu_p, logvar_p, mu_q, logvar_q).sum(-1),
            "standard": lambda: gaussian_kl(mu_q, logvar_q).sum(-1),
            "per dimension": lambda: gaussian_kl(mu_q, logvar_q, mu_p, logvar_p),
        }[kl_to]()
        next_state = transition(word, z, state)
        if feed == "decoded":
            next_state = transition(decode(z, state), z, state)
        word_hat = decode(z, next_state if feed == "new state" else state)
        return word_hat, kl, next_state

    return fn


@pytest.mark.parametrize(
    "wrong, says",
    [
        (_cell_step(z_from="prior"), "drawn from the prior"),
        (_cell_step(sigma=torch.exp), "exp(logvar) is the variance"),
        (_cell_step(sigma=lambda logvar: 0 * logvar), "the posterior's mean"),
        (_cell_step(kl_to="reversed"), "reversed"),
        (_cell_step(kl_to="standard"), "not N(0, I)"),
        (_cell_step(kl_to="per dimension"), "sum over them"),
        (_cell_step(feed="decoded"), "teacher forcing"),
        (_cell_step(feed="new state"), "h_{t-1}, the state before the word"),
        (lambda *args: _cell_step()(*args)[:2], "three tensors"),
    ],
)
def test_motion_cell_step_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_motion_cell_step(wrong)
    assert result.status == "wrong" and says in result.message, result


def _coupling(
    order="shift-first",
    offset=2.0,
    squash=torch.sigmoid,
    swap=False,
    reduce=True,
    stable=True,
    mask_output=True,
    mask_input=True,
    log_of="scale",
):
    def forward(x, mask, net):
        shift, raw = net(x * mask if mask_input else x).chunk(2, dim=-1)
        if swap:
            shift, raw = raw, shift
        scale = squash(raw + offset)
        moved = (x + shift) * scale if order == "shift-first" else x * scale + shift
        y = mask * x + (1 - mask) * moved if mask_output else moved
        log_scale = torch.nn.functional.logsigmoid(raw + offset) if stable else torch.log(scale)
        if log_of == "nothing":
            log_scale = scale
        terms = (1 - mask) * log_scale if mask_output else log_scale
        return y, terms.sum(dim=-1) if reduce else terms

    return forward


@pytest.mark.parametrize(
    "wrong, says",
    [
        (_coupling(order="scale-first"), "shift first"),
        (_coupling(swap=True), "shift u first"),
        (_coupling(offset=0.0), "Glow's offset"),
        (_coupling(squash=torch.exp), "not exp"),
        (_coupling(reduce=False), "one value per point"),
        (_coupling(stable=False), "logsigmoid"),
        (_coupling(mask_output=False), "conditioning half (mask = 1) must leave the layer unchanged"),
        (_coupling(mask_input=False), "read only the conditioning half"),
        (_coupling(log_of="nothing"), "not the scales"),
        (lambda x, mask, net: (_coupling()(x, mask, net)[0], -_coupling()(x, mask, net)[1]), "wrong sign"),
        (
            lambda x, mask, net: (
                _coupling()(x, mask, net)[0],
                torch.nn.functional.logsigmoid(net(x * mask).chunk(2, dim=-1)[1] + 2).sum(dim=-1),
            ),
            "counts the conditioning half",
        ),
        (lambda x, mask, net: _coupling()(x, mask, net)[0], "pair"),
    ],
)
def test_coupling_forward_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_coupling_forward(wrong)
    assert result.status == "wrong" and says in result.message, result


def _inverse(order="scale-first", sign=-1.0, mask_output=True):
    def inverse(y, mask, net):
        shift, raw = net(y * mask).chunk(2, dim=-1)
        scale = torch.sigmoid(raw + 2)
        moved = y / scale + sign * shift if order == "scale-first" else (y + sign * shift) / scale
        return mask * y + (1 - mask) * moved if mask_output else moved

    return inverse


@pytest.mark.parametrize(
    "wrong, says",
    [
        (_inverse(sign=1.0), "subtracting u"),
        (_inverse(order="shift-first"), "reverse order"),
        (_inverse(mask_output=False), "passes through the inverse unchanged"),
        (lambda y, mask, net: y, "is not x"),
    ],
)
def test_coupling_inverse_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_coupling_inverse(wrong)
    assert result.status == "wrong" and says in result.message, result


def _dct(scale_zero=None, scale=None, transpose=False, fixed_n=None, kind=2):
    def matrix(n_frames):
        n = fixed_n or n_frames
        k = torch.arange(n, dtype=torch.float64)[:, None]
        t = torch.arange(n, dtype=torch.float64)[None, :]
        angle = math.pi * (2 * t + 1) * k / (2 * n) if kind == 2 else math.pi * t * k / n
        s = torch.full((n, 1), math.sqrt(2 / n) if scale is None else scale, dtype=torch.float64)
        s[0] = math.sqrt(1 / n) if scale_zero is None else scale_zero
        d = s * torch.cos(angle)
        return d.T if transpose else d

    return matrix


@pytest.mark.parametrize(
    "wrong, says",
    [
        (_dct(transpose=True), "transposed"),
        (_dct(scale_zero=math.sqrt(2 / 8)), "row 0"),
        (_dct(scale_zero=1.0, scale=1.0), "scale"),
        (_dct(kind=1), "cosines are wrong"),
        (_dct(fixed_n=8), "T = n_frames"),
    ],
)
def test_dct_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_dct_matrix(wrong)
    assert result.status == "wrong" and says in result.message, result


def _contrastive(same_term, apart_term, reduce=False, safe=True):
    def loss(mu_a, mu_b, same, margin):
        squared = (mu_a - mu_b).pow(2).sum(-1)
        d = squared.clamp_min(1e-12).sqrt() if safe else squared.sqrt()
        out = torch.where(same, same_term(d), apart_term(d, margin))
        return out.mean() if reduce else out

    return loss


HALF_SQ = lambda d: 0.5 * d**2  # noqa: E731
HINGE = lambda d, m: 0.5 * torch.relu(m - d) ** 2  # noqa: E731


@pytest.mark.parametrize(
    "wrong, says",
    [
        (_contrastive(HALF_SQ, HINGE, reduce=True), "one loss per pair"),
        (_contrastive(lambda d: d**2, lambda d, m: torch.relu(m - d) ** 2), "factor 1/2"),
        (_contrastive(lambda d: HINGE(d, 3.0), lambda d, m: HALF_SQ(d)), "swapped"),
        (_contrastive(HALF_SQ, lambda d, m: 0.5 * torch.relu(m - d)), "hinge is squared"),
        (_contrastive(HALF_SQ, lambda d, m: 0.5 * torch.relu(m - d**2) ** 2), "not d^2"),
        (_contrastive(lambda d: 0.5 * d, HINGE), "squared distance"),
        (_contrastive(HALF_SQ, HINGE, safe=False), "NaN"),
    ],
)
def test_contrastive_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_contrastive_loss(wrong)
    assert result.status == "wrong" and says in result.message, result


def _reach(combine="max", include_own=False, forward=False):
    def reach(parents, bones):
        out = np.zeros(len(parents))
        order = range(1, len(parents)) if forward else range(len(parents) - 1, 0, -1)
        for j in order:
            value = out[j] + bones[j]
            out[parents[j]] = max(out[parents[j]], value) if combine == "max" else out[parents[j]] + value
        return out + bones if include_own else out

    return reach


@pytest.mark.parametrize(
    "wrong, says",
    [
        (_reach(combine="sum"), "longest single path"),
        (_reach(include_own=True), "own bone"),
        (_reach(forward=True), "visit children before"),
        (lambda parents, bones: np.zeros(len(parents) - 1), "one L_j per joint"),
    ],
)
def test_subtree_reach_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_subtree_reach(wrong)
    assert result.status == "wrong" and says in result.message, result


def _loop(
    window=lambda control, t, history: control[:, t : t + history + 1],
    scale=True,
    update=True,
    carry=True,
    keep=lambda past: past,
    newest_first=False,
):
    def loop(invert_frame, control, seed_pose, noise, temperature):
        history = seed_pose.shape[1]
        past, state, poses = seed_pose, None, []
        for t in range(control.shape[1] - history):
            visible = keep(past.flip(1) if newest_first else past)
            cond = torch.cat([visible.flatten(1), window(control, t, history).flatten(1)], dim=1)
            pose, new_state = invert_frame((temperature if scale else 1.0) * noise[:, t], cond, state)
            state = new_state if carry else None
            poses.append(pose)
            if update:
                past = torch.cat([past[:, 1:], pose[:, None]], dim=1)
        return torch.stack(poses, dim=1)

    return loop


@pytest.mark.parametrize(
    "wrong, says",
    [
        (
            _loop(window=lambda control, t, history: control[:, t + 1 : t + history + 2]),
            "window is control[:, t",
        ),
        (
            _loop(window=lambda control, t, history: control[:, t : t + history + 1].flip(1)),
            "current control last",
        ),
        (_loop(newest_first=True), "oldest first"),
        (_loop(scale=False), "not scaled"),
        (_loop(update=False), "update the history"),
        (_loop(carry=False), "carry the LSTM state"),
        (
            _loop(
                keep=lambda past: (
                    past * (torch.rand(past.shape, generator=torch.Generator().manual_seed(0)) > 0.95)
                )
            ),
            "dropout is for training only",
        ),
        (lambda *args: _loop()(*args).transpose(0, 1), "along dim 1"),
        (lambda frame, control, seed, noise, temperature: noise, "once per generated frame"),
    ],
)
def test_sample_loop_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_sample_loop(wrong)
    assert result.status == "wrong" and says in result.message, result


def _skating(horizontal=True, per_second=True, both_ends=True, pooled=True):
    def skating(feet, contacts, fps):
        if not pooled and feet.ndim == 4:
            return float(np.mean([_skating()(f, c, fps) for f, c in zip(feet, contacts)]))
        step = feet[..., 1:, :, :] - feet[..., :-1, :, :]
        speed = np.linalg.norm(step[..., :2] if horizontal else step, axis=-1) * (fps if per_second else 1)
        planted = contacts[..., :-1, :] & contacts[..., 1:, :] if both_ends else contacts[..., :-1, :]
        return float(speed[planted].mean())

    return skating


def _weights(floor="relative", normalise="mean", floor_first=True):
    def weights(reach, leaf_floor):
        def raise_(r):
            if floor == "none":
                return r
            return np.maximum(r, leaf_floor * r.max() if floor == "relative" else leaf_floor)

        def scale(r):
            return r / getattr(r, normalise)()

        return scale(raise_(reach)) if floor_first else raise_(scale(reach))

    return weights


def _keep(draw=lambda u, p: u >= p, rescale=lambda p: 1 / (1 - p), seeded=True, at_generation=False):
    def keep_mask(batch, frames, history, dropout, generator, training):
        if not training and not at_generation:
            return torch.ones(batch, frames, history)
        u = torch.rand(batch, frames, history, generator=generator if seeded else None)
        return draw(u, dropout).float() * rescale(dropout)

    return keep_mask


def _given(tile=torch.repeat_interleave, keep_given=True, frame_axis=True):
    def given(poses, mask):
        flags = mask if keep_given else ~mask
        channels = tile(flags, 3, dim=-1) if tile is torch.repeat_interleave else flags.repeat(3)
        return poses * (channels[..., None, :] if frame_axis else channels).to(poses.dtype)

    return given


def _kl(mu_q, logvar_q, mu_p, logvar_p):
    """KL(N(mu_q, .) || N(mu_p, .)) summed per sequence (B,), for latents (B, C, L)."""
    return gaussian_kl(mu_q, logvar_q, mu_p, logvar_p).sum(dim=(1, 2))


def _prior(trace=lambda logvar, s2: logvar.exp() / s2, log_det_sign=-1.0, on_mean=0.0, reduce=True):
    def prior(mu, logvar, prior_variance):
        terms = trace(logvar, prior_variance) + log_det_sign * logvar + on_mean * mu**2 / prior_variance
        return terms.sum(dim=-1) if reduce else terms

    return prior


@pytest.mark.parametrize(
    "checker, wrong, says",
    [
        ("check_foot_skating", _skating(horizontal=False), "horizontal"),
        ("check_foot_skating", _skating(per_second=False), "multiply the per-frame displacement by fps"),
        ("check_foot_skating", _skating(both_ends=False), "*both* ends"),
        ("check_foot_skating", _skating(pooled=False), "pool the planted pairs"),
        (
            "check_foot_skating",
            lambda feet, contacts, fps: _skating()(feet, contacts, fps) * np.ones(2),
            "one number",
        ),
        ("check_impact_weights", _weights(floor="none"), "end effectors get λ = 0"),
        ("check_impact_weights", _weights(floor="absolute"), "a fraction of the largest"),
        ("check_impact_weights", _weights(normalise="sum"), "sum to 1"),
        ("check_impact_weights", _weights(normalise="max"), "largest weight is 1"),
        ("check_impact_weights", _weights(floor_first=False), "floor first"),
        (
            "check_impact_weights",
            lambda reach, leaf_floor: _weights()(reach, leaf_floor)[1:],
            "one λ_j per joint",
        ),
        ("check_keep_mask", _keep(rescale=lambda p: 1.0), "not rescaled"),
        ("check_keep_mask", _keep(rescale=lambda p: 1 - p), "divide by it instead"),
        ("check_keep_mask", _keep(draw=lambda u, p: u < p), "probability of *dropping*"),
        ("check_keep_mask", _keep(seeded=False), "generator=generator"),
        ("check_keep_mask", _keep(at_generation=True), "for training only"),
        ("check_keep_mask", _keep(), "p = 1 gives NaN or inf"),
        ("check_keep_mask", _keep(rescale=lambda p: torch.tensor(1.0) / (1 - p)), "p = 1 gives NaN or inf"),
        (
            "check_keep_mask",
            lambda b, f, h, p, g, training: _keep()(f, b, h, p, g, training),
            "(batch, frames, history)",
        ),
        ("check_given_trajectories", _given(tile=None), "repeat_interleave"),
        ("check_given_trajectories", _given(keep_given=False), "zeroed the given ones"),
        ("check_given_trajectories", _given(frame_axis=False), "add one (mask[..., None, :])"),
        (
            "check_given_trajectories",
            lambda poses, mask: poses[..., mask.repeat_interleave(3, dim=-1)],
            "keep the shape",
        ),
        ("check_given_trajectories", lambda poses, mask: _given()(poses.detach(), mask), "no gradient"),
        ("check_prior_kl", lambda mq, lq, mp, lp: _kl(mp, lp, mq, lq), "swapped"),
        ("check_prior_kl", lambda mq, lq, mp, lp: _kl(mq, lq, 0.0, 0.0), "N(0, I)"),
        ("check_prior_kl", lambda mq, lq, mp, lp: gaussian_kl(mq, lq, mp, lp), "one KL per sequence (B,)"),
        ("check_prior_kl", lambda mq, lq, mp, lp: _kl(mq, lq, mp, lp).mean(), "not its mean"),
        ("check_prior_kl", lambda mq, lq, mp, lp: gaussian_kl(mq, lq, mp, lp).mean(dim=(1, 2)), "sum them"),
        ("check_prior_kl", lambda mq, lq, mp, lp: 2 * _kl(mq, lq, mp, lp), "factor 1/2"),
        ("check_prior_kl", lambda mq, lq, mp, lp: _kl(mq.detach(), lq, mp, lp), "no gradient"),
        ("check_covariance_prior", _prior(log_det_sign=1.0), "wrong sign of the log-determinant"),
        ("check_covariance_prior", _prior(on_mean=1.0), "no prior on the means"),
        ("check_covariance_prior", _prior(reduce=False), "sum over the D code dimensions"),
        ("check_covariance_prior", _prior(trace=lambda logvar, s2: logvar.exp() / s2**2), "not its square"),
        ("check_covariance_prior", _prior(trace=lambda logvar, s2: logvar / s2), "exp(logvar)"),
        ("check_covariance_prior", _prior(trace=lambda logvar, s2: logvar.exp() / 0.05), "not a constant"),
        (
            "check_covariance_prior",
            lambda mu, logvar, s2: _prior()(mu, logvar, s2) - logvar.shape[-1] * (1 - math.log(s2)),
            "minus its minimum",
        ),
    ],
)
def test_checker_names_the_mistake(checker, wrong, says) -> None:
    result = getattr(exercises, checker)(wrong)
    assert result.status == "wrong" and says in result.message, result


def _ancestral(mean_x0=None, noise_scale=None, last=None):
    """Chapter 11's ancestral step with one piece replaced: ``mean_x0(beta, now, before)`` the coefficient
    of x0_hat, ``noise_scale(beta, variance)`` the noise's factor, ``last(x0_hat, noise, betas)`` the t = 0
    step."""

    def step(x0_hat, x_t, t, betas, noise):
        alpha_bar = torch.cumprod(1 - betas, dim=0)
        if t == 0:
            return x0_hat if last is None else last(x0_hat, noise, betas)
        beta, now, before = betas[t], alpha_bar[t], alpha_bar[t - 1]
        coefficient = beta * before.sqrt() / (1 - now) if mean_x0 is None else mean_x0(beta, now, before)
        mean = coefficient * x0_hat + (1 - before) * (1 - beta).sqrt() / (1 - now) * x_t
        variance = beta * (1 - before) / (1 - now)
        return mean + (variance.sqrt() if noise_scale is None else noise_scale(beta, variance)) * noise

    return step


@pytest.mark.parametrize(
    "wrong, says",
    [
        (_ancestral(noise_scale=lambda beta, variance: 0 * beta), "no noise was added"),
        (_ancestral(noise_scale=lambda beta, variance: variance), "standard deviation"),
        (_ancestral(noise_scale=lambda beta, variance: beta.sqrt()), "forward step's variance"),
        (_ancestral(last=lambda x0_hat, noise, betas: x0_hat + betas[0].sqrt() * noise), "at t = 0 noise"),
        (_ancestral(last=lambda x0_hat, noise, betas: 0.5 * x0_hat), "index t - 1 = -1"),
        (_ancestral(mean_x0=lambda beta, now, before: beta * now.sqrt() / (1 - now)), "the mean"),
        (lambda x0_hat, x_t, t, betas, noise: x0_hat, "only the last step"),
        (lambda x0_hat, x_t, t, betas, noise: x0_hat[:1], "shape"),
    ],
)
def test_ancestral_step_checker_names_the_mistake(wrong, says) -> None:
    result = exercises.check_ancestral_step(wrong)
    assert result.status == "wrong" and says in result.message, result


# The hooks the end-of-chapter exercises use instead of edits to the package.


def test_motion_cell_temperature_scales_the_prior_noise() -> None:
    from test_motion_cell_common import motion_cell, perturb

    model = motion_cell().eval()
    perturb(model.word_decoder.net[-1].weight, 0.1)  # a decoder that moves
    action, body = torch.tensor([0, 1]), torch.tensor([1, 0])

    def sample(**kwargs) -> torch.Tensor:
        return model.generate(action, body, 7, torch.Generator().manual_seed(3), **kwargs)

    assert torch.equal(sample(), sample(temperature=1.0))
    cool, hot = sample(temperature=0.0), sample(temperature=2.0)
    assert cool.shape == hot.shape == (2, 7, 90) and not torch.equal(cool, hot)
    with pytest.raises(ValueError, match="temperature"):
        sample(temperature=-1.0)


def test_moglow_history_dropout_can_be_overridden_in_a_subclass() -> None:
    from motionlab.models.moglow import MoGlow, MoGlowConfig

    class WholeWindow(MoGlow):
        def keep_mask(self, batch, frames, generator=None):
            keep = super().keep_mask(batch, frames, generator)
            calls.append((batch, frames))
            return keep[..., :1].expand_as(keep)  # one flag per frame for the whole window

    calls: list[tuple[int, int]] = []
    model = WholeWindow(
        MoGlowConfig(pose_dim=6, control_dim=2, history=3, steps=1, hidden=4, cond_features=3)
    )
    pose, control = torch.randn(2, 9, 6), torch.randn(2, 9, 2)
    model.train()(pose, control, torch.Generator().manual_seed(0))
    assert calls == [(2, 6)]
    model.eval()(pose, control)
    assert calls == [(2, 6)]
    full = MoGlow(model.cfg)
    full.load_state_dict(model.state_dict())
    assert torch.equal(full.eval()(pose, control), model(pose, control))


def exercise_sections() -> list[tuple[str, str]]:
    """(chapter file name, its '## Exercises' text) of every chapter and appendix."""
    sections = []
    for path in numbered_notebooks(NOTEBOOKS):
        text = "\n".join("".join(c["source"]) for c in json.loads(path.read_text())["cells"])
        if "## Exercises" in text:
            sections.append((path.name, text.split("## Exercises", 1)[1].split("\n## ", 1)[0]))
    return sections


@pytest.mark.parametrize("chapter, text", exercise_sections(), ids=[c[:2] for c, _ in exercise_sections()])
def test_end_of_chapter_exercises_say_how_long_and_how_to_tell_success(chapter: str, text: str) -> None:
    items = re.split(r"\n\d+\. ", "\n1. " + text.split("\n1. ", 1)[1])[1:]  # exercise 1 included
    assert len(items) >= 4, f"{chapter}: expected the numbered exercises"
    for number, item in enumerate(items, 1):
        assert re.search(r"\d+ (min|hours?)", item), f"{chapter} exercise {number}: no time estimate"
        assert "**Success:**" in item, f"{chapter} exercise {number}: no success criterion"
        assert not re.search(r"(edit|change|in) `motionlab/", item), (
            f"{chapter} exercise {number}: edits the package"
        )
    answers = NOTEBOOKS / "solutions" / f"{chapter.removesuffix('.ipynb')}_exercises.md"
    assert answers.exists(), f"{chapter}: no worked answers at {answers.name}"
    assert answers.read_text().count("\n## ") >= len(items), f"{chapter}: an exercise without a worked answer"
