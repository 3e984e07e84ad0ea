"""Environment steps per second of SEPG through ``sepg.gym`` beside a plain-Python REINFORCE
loop with the same linear Gaussian policy on the same gymnasium environment.

Both loops collect the same number of trajectories of the same horizon per iteration and
update the policy once per iteration; the ratio says how much the Rust estimation, safe steps
and bookkeeping cost compared with the cheapest possible Python update (one numpy
REINFORCE gradient step). The loops are measured in the same process, interleaved (one run of
each loop per repetition, so that a change of the machine's load affects all of them), each
as steps per second of wall-clock time and per second of CPU time (``time.process_time``,
the figure a shared machine's load disturbs least); the table gives the medians over
``--repeats`` repetitions and the range of the per-repetition ratios.

    .venv/bin/python crates/python/benches/gym_steps.py [--env MountainCarContinuous-v0]
"""

import argparse
import statistics
import time

import gymnasium as gym
import numpy as np

from sepg import gym as sepg_gym


def features(obs):
    return np.array([obs[0], 10.0 * obs[1], 1.0])


def reinforce(env, iterations, n, horizon, seed):
    """REINFORCE (eq. 2.1) with a constant step, the policy N(V phi, sigma^2)."""
    rng = np.random.default_rng(seed)
    V, sigma, gamma, alpha = np.full((1, 3), -0.1), 1.0, 0.99, 1e-4
    steps = 0
    start, cpu = time.perf_counter(), time.process_time()
    for it in range(iterations):
        grads, returns = [], []
        for i in range(n):
            obs, _ = env.reset(seed=seed + it * n + i)
            score, ret, disc = np.zeros_like(V), 0.0, 1.0
            for _ in range(horizon):
                phi = features(obs)
                mu = V @ phi
                a = mu + sigma * rng.standard_normal(1)
                obs, r, terminated, truncated, _ = env.step(a)
                score += np.outer((a - mu) / sigma**2, phi)
                ret += disc * r
                disc *= gamma
                steps += 1
                if terminated or truncated:
                    break
            grads.append(score * ret)
            returns.append(ret)
        V = V + alpha * np.mean(grads, axis=0)
    return steps / (time.perf_counter() - start), steps / (time.process_time() - cpu)


def sepg_run(env, algorithm, iterations, n, horizon, seed):
    # No reference batch (reference_batch=0, the thesis's pseudocode): every step measured
    # belongs to an iteration, as in the REINFORCE loop. The reference batch's trajectories
    # need no scores and would raise the rate.
    run = sepg_gym.GymRun(
        env, features, gamma=0.99, r_max=100.0, m_phi=1.2, algorithm=algorithm,
        n_trajectories=n, horizon=horizon, seed=seed, show_derivation=False, reference_batch=0,
    )
    start, cpu = time.perf_counter(), time.process_time()
    run.run(iterations)
    steps = run.records[-1]["steps"]
    return steps / (time.perf_counter() - start), steps / (time.process_time() - cpu)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--env", default="MountainCarContinuous-v0")
    p.add_argument("--iterations", type=int, default=3)
    p.add_argument("--n", type=int, default=60)
    p.add_argument("--horizon", type=int, default=200)
    p.add_argument("--repeats", type=int, default=3)
    a = p.parse_args()
    env = gym.make(a.env)
    algorithms = ("sepg-zv", "sepg-mi", "adastep")
    rates = {name: [] for name in ("reinforce", *algorithms)}
    for s in range(a.repeats):
        rates["reinforce"].append(reinforce(env, a.iterations, a.n, a.horizon, s))
        for algorithm in algorithms:
            rates[algorithm].append(sepg_run(env, algorithm, a.iterations, a.n, a.horizon, s))
    print(f"{a.env}: N = {a.n}, H = {a.horizon}, {a.iterations} iterations, {a.repeats} interleaved repetitions")
    print("| loop | steps/s (wall) | ratio (range) | steps/CPU-s | ratio (range) |")
    print("|---|---:|---:|---:|---:|")
    for name, label in (("reinforce", "plain-Python REINFORCE (numpy)"),
                        *((alg, f"sepg.gym {alg}") for alg in algorithms)):
        cells = []
        for k in (0, 1):
            ratios = sorted(r[k] / b[k] for r, b in zip(rates[name], rates["reinforce"]))
            median = statistics.median(r[k] for r in rates[name])
            cells.append(f"{median:,.0f} | {statistics.median(ratios):.2f} ({ratios[0]:.2f}-{ratios[-1]:.2f})")
        print(f"| {label} | {' | '.join(cells)} |")


if __name__ == "__main__":
    main()
