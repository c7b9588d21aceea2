"""A bank of answers that crash (wrong shapes, transposes, ragged arrays, weights that underflow or are not
normalised, wrong return types), each in place of the model answer with its blank's visible checks, in the
solved notebook run in this process (autograder/authoring/visible_checks.py): the message a student reads
names the blank, the line of theirs that raised, and what to do, from the check's own hint (issue 34)."""

from __future__ import annotations

from typing import NamedTuple

import pytest

from autograder import cells
from autograder.authoring.visible_checks import visible_message, visible_verdicts
from autograder.labs import Lab
from course.checks import LINE_WIDTH


class Crash(NamedTuple):
    """An edit of a blank's model answer (``find`` replaced by ``replace``) that makes a visible check fail
    with an error, and a phrase of its message that names the fix."""

    blank: str
    slug: str
    find: str
    replace: str
    says: str
    raises: str = ""
    """The type of error the student's function raises; "" for a wrong return value that the check helpers
    refuse (an AssertionError), whose message names what was returned instead."""


CRASHES = {
    "train-kf": [
        Crash("gain_information_form", "last-factor-not-transposed", "B_inv + H.T @ RinvH, RinvH.T)",
              "B_inv + H.T @ RinvH, RinvH)", "K is n x m", "ValueError"),
        Crash("gain_covariance_form", "solves-for-K-not-its-transpose", "np.linalg.solve(S, H @ B).T",
              "np.linalg.solve(S, B @ H.T)", "K is n x m", "ValueError"),
        # the fairness review of the messages: the explanation spoke of solve(A, b), and A is this lab's model matrix
        Crash("gain_covariance_form", "solves-for-K-transposed-with-B-H-transposed", "np.linalg.solve(S, H @ B).T",
              "np.linalg.solve(S, B @ H.T).T", "np.linalg.solve(M, b) got shapes that do not fit", "ValueError"),
        Crash("process_noise", "ragged-rows", "np.array([[h * h, h], [h, 1.0]])", "np.array([[h * h, h], [h]])",
              "the shape of the arrays beside it", "ValueError"),
        Crash("kupdate", "innovation-vector-on-the-left", "y - H @ x_f", "y - x_f @ H", "the order of the factors",
              "ValueError"),
        Crash("kupdate", "identity-of-size-2", "B_a = B_f - K @ H @ B_f",
              "B_a = (np.eye(2) - K @ H) @ B_f", "np.eye(len(x_f))", "ValueError"),
        Crash("nees", "stack-of-vectors-as-one-matrix", "np.linalg.solve(covariances, errors[:, :, None])[:, :, 0]",
              "np.linalg.solve(covariances, errors)", "errors[..., None]"),
        Crash("nees", "returns-nothing", "    return np.sum(errors * scaled, axis=1)",
              "    np.sum(errors * scaled, axis=1)", "it is None"),
    ],
    "castaway-bob": [
        Crash("kalman_gain", "solves-with-P-H-transposed", "np.linalg.solve(S, H @ P).T", "np.linalg.solve(S, P @ H.T).T",
              "n x m = 4 x 2", "ValueError"),
        Crash("joseph_covariance", "identity-of-size-2", "np.eye(P.shape[0])", "np.eye(2)",
              "(1 - k)^2 P + k^2 R", "ValueError"),
        Crash("trailing_mean", "returns-nothing", "    return estimates", "    estimates", "it is None"),
        Crash("run_rank4", "input-of-size-2", "u = np.concatenate((dt * flow(xs[k - 1, :2], t[k - 1]), [0.0, 0.0]))",
              "u = dt * flow(xs[k - 1, :2], t[k - 1])", "of kalman_step", "ValueError"),
    ],
    "nonlinear-filters": [
        Crash("cubature_points", "ragged-points", "np.sqrt(n) * np.vstack((np.eye(n), -np.eye(n)))",
              "np.sqrt(n) * np.array([np.eye(n), -np.eye(n)[0]])", "One row per point", "ValueError"),
        Crash("sigma_point_predict", "weights-on-the-right", "m_new = w @ Y", "m_new = Y @ w", "a sum over the rows",
              "ValueError"),
        Crash("sigma_point_update", "gain-solved-untransposed", "K = np.linalg.solve(P_yy, P_xy.swapaxes(-1, -2))",
              "K = np.linalg.solve(P_yy, P_xy)", "K = P_xy P_yy^-1 is n x p", "ValueError"),
        Crash("ekf_update", "H-not-transposed", "S = H @ P @ H.swapaxes(-1, -2) + R", "S = H @ P @ H + R",
              "S = H P H^T + R is p x p", "ValueError"),
    ],
    "reentry-pf": [
        Crash("tracking_dynamics", "zero-as-a-number", "np.zeros_like(beta)", "0.0", "np.zeros_like(beta)",
              "ValueError"),
        Crash("tracking_dynamics", "ragged-array", "np.stack([-v, G - G * rho * v**2 / (2 * beta), np.zeros_like(beta)])",
              "np.array([-v, G - G * rho * v**2 / (2 * beta), 0.0])", "np.zeros_like(beta)", "ValueError"),
        Crash("initial_cloud", "std-not-a-column", "PRIOR_STD[:, None] * rng.standard_normal((3, N))",
              "PRIOR_STD * rng.standard_normal((3, N))", "One column per particle", "ValueError"),
        Crash("pf_step", "weights-underflow", "w_hat = np.exp(log_w_hat - np.max(log_w_hat))\n    w_hat /= np.sum(w_hat)",
              "w_hat = np.exp(log_w_hat) / np.sum(np.exp(log_w_hat))\n    k = rng.choice(N, size=N, p=w_hat)",
              "work with log-weights", "ValueError"),
        Crash("pf_step", "weights-not-normalised", "    w_hat /= np.sum(w_hat)",
              "    k = rng.choice(N, size=N, p=w_hat)", "normalise the weights", "ValueError"),
    ],
    "reentry-srekf": [
        Crash("conditional", "R2-not-transposed", "mu[idx_a] + R2.T @ solve_triangular",
              "mu[idx_a] + R2 @ solve_triangular", "so (31) takes R2^T", "ValueError"),
        Crash("sqrt_time_update", "S-without-the-noise-block", "np.linalg.qr(S_z @ J.T", "np.linalg.qr(S @ J.T",
              "S_z = block_diag(S, S_Q)", "ValueError"),
        Crash("sqrt_measurement_update", "zero-block-n-by-n", "[S_R, np.zeros((m, n))]", "[S_R, np.zeros((n, n))]",
              "0 is m x n", "ValueError"),
    ],
}
"""Per lab, answers that crash or return what is not an array, each with a phrase of its message that names the fix:
the check's hint for the call where the check has one, else the sentence on what such an error usually means."""


@pytest.mark.filterwarnings("default::RuntimeWarning")  # as in a student's kernel: a warning does not stop a cell
@pytest.mark.parametrize("lab", [Lab(lab_id) for lab_id in sorted(CRASHES)], ids=sorted(CRASHES))
def test_a_crash_in_a_blank_names_the_blank_its_line_and_the_checks_hint(lab: Lab):
    """Every answer of the lab's bank fails its visible checks with a message, wrapped to LINE_WIDTH, that names
    the blank and its line that raised (for a crash) and says what to fix."""
    model = cells.model_answers(cells.read(lab.source_notebook))
    answers = []
    for crash in CRASHES[lab.id]:
        assert model[crash.blank].count(crash.find) == 1, f"{crash.slug}: {crash.find!r} is not once in the answer"
        answers.append((f"{crash.blank}/{crash.slug}", crash.blank, model[crash.blank].replace(crash.find, crash.replace)))
    verdicts = visible_verdicts(lab, answers)
    problems = []
    for crash in CRASHES[lab.id]:
        error = verdicts[f"{crash.blank}/{crash.slug}"]
        message = "" if error is None else visible_message(error, list(model))
        flat = " ".join(message.split())
        wanted = [f"{crash.raises} in your {crash.blank}", "It was raised at the line"] if crash.raises else []
        wanted += [crash.says] if crash.says else []
        missing = [phrase for phrase in wanted if phrase not in flat]
        too_wide = [line for line in message.splitlines() if len(line) > LINE_WIDTH and " " in line.strip()]
        if error is None or missing or too_wide:
            problems.append(f"{crash.blank}/{crash.slug}: missing {missing}, too wide {too_wide}:\n{message or 'passes'}")
    assert not problems, "\n\n".join(problems)

