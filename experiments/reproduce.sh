#!/usr/bin/env bash
# Remake every sweep and figure of docs/results.md from nothing.
#
#     bash experiments/reproduce.sh      # the scale of docs/results.md: 3 seeds (8 for the
#                                        # two-agent experiment and for one and two agents
#                                        # with different walls, 11 for the one-agent one,
#                                        # 6 for the paper's temperatures); 40,000 steps a run
#                                        # with one or two agents and for the temperatures,
#                                        # 15,000 for the wall variants
#     SEEDS=8 STEPS=80000 bash experiments/reproduce.sh
#                                        # the paper's full scale (see below)
#
# Run lengths: STEPS, when given, sets every sweep's; MULTI_STEPS (multi_agent), SINGLE_STEPS
# (single_agent), TEMPERATURE_STEPS (both temperature presets) and WALL_STEPS (the wall presets)
# set their sweeps' and win over STEPS. Each sweep is checkpointed every 1,000 steps into
# runs/paper/<preset>; run the script again after an interruption (a closed session, Ctrl-C, a
# scheduler's SIGTERM) and every sweep continues from its newest checkpoint (resume=true) instead of
# starting over. Asking for more steps later continues the same sweeps further. Then the metrics are
# copied into experiments/results/ and the page's figures and tables are redrawn from them.
#
# Seeds: SEEDS (default 3) per policy or setting of every preset; at the page's scale (SEEDS not
# given) the two-agent experiment (multi_agent) has MULTI_SEEDS (default 8) in all and the
# one-agent experiment (single_agent) SINGLE_SEEDS (default 11), and one agent with a different
# texture on every wall (single_agent_walls_different) SINGLE_WALL_SEEDS (default 8), and two agents
# with a different texture on every wall (multi_agent_walls_different) MULTI_WALL_SEEDS (default
# 8), and the paper's Boltzmann temperatures (boltzmann_temperatures) TEMPERATURE_SEEDS (default
# 6); SEEDS, when given, sets them all, and each of those knobs wins over it, as with the run
# lengths. The first SEEDS run in runs/paper/<preset> and the rest, as they ran for the page, in
# sweeps of their own of at most 3 seeds each (runs/paper/<preset>.seeds-3-5,
# runs/paper/<preset>.seeds-6-7 and, for the one-agent experiment, which grew from 8 seeds to 11,
# runs/paper/single_agent.seeds-8-10: most fit a 3-hour session on 2 cores; the 15 runs of a
# temperature part take three), which the page reads with the first as one experiment
# (analysis.merge_sweeps).
#
# Wall time on a 2-core AMD EPYC (lscpu "AMD EPYC", family 25 model 1), CPU only, one sweep at a
# time, measured from the sweeps' own progress lines (run-steps/s = runs x steps per second):
#   multi_agent    9 runs x 40,000 steps   5 h 51 min (steps 500-15,000 in 2 h 21 min at 15.5 run-steps/s, 15,000-20,000 in 40 min at 18.7, 20,000-40,000 in 2 h 46 min at 18.1)
#   multi_agent.seeds-3-5  9 runs x 40,000 steps   about 4 h 40 min (19,300 steps in 2 h 29 min, 19,000-40,000 in 2 h 8 min at 24.6 run-steps/s),
#   multi_agent.seeds-6-7  6 runs x 40,000 steps   about 2 h 10 min (500 steps in 2 min, then 500-40,000 in 2 h 8 min at about 31 run-steps/s, paused 4 min for a test run),
#                          both on a 2-core Intel Xeon (lscpu "Intel(R) Xeon(R) Processor", family 6 model 167): not comparable with the rows above
#   single_agent   9 runs x 40,000 steps   3 h 16 min (1 h 14 min to 15,000 steps, then 15,000-40,000 in 2 h 2 min at 30.8 run-steps/s)
#   single_agent.seeds-3-5  9 runs x 40,000 steps   2 h 7 min (45-47 run-steps/s), on the 2-core Intel Xeon above: not comparable with the AMD rows
#   single_agent.seeds-6-7  6 runs x 40,000 steps   1 h 6 min (61 run-steps/s; 46 while a test ran beside it), on the same Intel Xeon
#   single_agent.seeds-8-10  9 runs x 40,000 steps   3 h 40 min over 2 sessions (22,000 steps in 2 h 11 min at 23.7-25.5 run-steps/s with tests and a CI run beside it, 22,000-40,000 in 1 h 29 min at 30 alone), on a 2-core Intel Xeon @ 2.80GHz (lscpu family 6 model 106)
#   boltzmann_temperatures  15 runs x 40,000 steps   9 h 5 min (7,000 steps in 1 h 57 min at 15.3 run-steps/s, 7,000-26,000 in 4 h 22 min at 18.1, 26,000-40,000 in 2 h 47 min at 21.0)
#   boltzmann_temperatures.seeds-3-5  15 runs x 40,000 steps   8 h 32 min in eight stretches (23-27 run-steps/s alone, 13-28 with tests and analysis beside it), on the Intel Xeon above
#   boltzmann_low_temperatures  12 runs x 40,000 steps   7 h 37 min (14,000 steps in 2 h 28 min, 14,000-28,000 in 2 h 51 min, 28,000-40,000 in 2 h 18 min at 17.4 run-steps/s; 15-19 throughout)
#   single_agent_walls_different  3 runs x 15,000 steps   30 min (25.9 run-steps/s)
#   single_agent_walls_different.seeds-3-5  3 runs x 15,000 steps   14 min (56-59 run-steps/s), on the Intel Xeon above
#   single_agent_walls_different.seeds-6-7  2 runs x 15,000 steps   8 min (65-68 run-steps/s), on the same Intel Xeon
#   multi_agent_walls_different   9 runs x 15,000 steps   59 min (38.3 run-steps/s), on another 2-core AMD
#                                 EPYC (family 26 model 2, with AVX-512 and bf16): not comparable with the rows above
#   multi_agent_walls_different.seeds-3-5  9 runs x 15,000 steps   1 h 40 min (26.5-30 run-steps/s alone; paused about 10 min), on the Intel Xeon above
#   multi_agent_walls_different.seeds-6-7  6 runs x 15,000 steps   1 h 16 min (18.9-22.1 run-steps/s; tests ran beside it for 17 min), on the AMD EPYC of the first rows
#   the page (snapshot, figures, claims)     about 5 s
#   temperature_evidence.py                 about 1 min a sweep
#   reconstruction_evidence.py              about 2 min a sweep of 9 runs with 4 checkpoints (beside a running sweep)
#
# Claim 6b (trembling) needs the order of actions, which the page's multi_agent sweeps ran too
# early to record; the page reads it from a side experiment with the same settings, 6 seeds x
# 20,000 steps in two sweeps of 3 (each about 3 h on the AMD EPYC above, over two or three
# sessions, 7-21 run-steps/s):
#     python -m mjx_curio.sweep preset=multi_agent seeds=3 steps=20000 checkpoint_every=1000 out=runs/paper/multi_agent.order
#     python -m mjx_curio.sweep preset=multi_agent seeds=3 first_seed=3 steps=20000 checkpoint_every=1000 out=runs/paper/multi_agent.order.seeds-3-5
# This script does not run it: a multi_agent sweep made now records the order itself, and claim
# 6b reads that first. Such a sweep also records the window moments with which claim 8 correlates
# the self-model's predictions with the curiosity obtained step by step; the committed ones do not,
# so claim 8 reads a second side experiment, 6 seeds x 20,000 steps in two sweeps of 3 (each about
# 2 h 30 min alone: on the AMD EPYC above, and at 19.8 run-steps/s on a 2-core Intel Xeon @ 2.80GHz,
# lscpu family 6 model 106), which this script does not run either:
#     python -m mjx_curio.sweep preset=multi_agent seeds=3 steps=20000 checkpoint_every=1000 out=runs/paper/multi_agent.per_step
#     python -m mjx_curio.sweep preset=multi_agent seeds=3 first_seed=3 steps=20000 checkpoint_every=1000 out=runs/paper/multi_agent.per_step.seeds-3-5
#     python experiments/self_model_evidence.py runs/paper/multi_agent.per_step   # about 6 min beside a running sweep
#     python experiments/self_model_evidence.py runs/paper/multi_agent.per_step.seeds-3-5   # its table pools both
# (the evidence: how much of each step's curiosity is sampling noise that no self-model can foresee,
# docs/results/self_model_noise.json, quoted under claim 8; spread_evidence.py below reads both too).
# Claim 1's fall and rise are taken apart into the world model's error and the posterior's spread
# on a third side experiment, one agent under epsilon-greedy (fig. 8's setting), which records the
# spread (every sweep made now does; the committed presets ran before), 4 seeds x 40,000 steps
# (1 h 44 min on the AMD EPYC above, 13 min of it paused; 32-36 run-steps/s alone), not run by
# this script:
#     python -m mjx_curio.sweep preset=single_agent policies=eps seeds=4 steps=40000 checkpoint_every=1000 out=runs/paper/single_agent.spread
#     python experiments/spread_evidence.py runs/paper/single_agent.spread   # and on both parts of multi_agent.per_step
# (the second: each latent dimension's posterior variance at every kept checkpoint,
# docs/results/posterior_dims.json, shown under claim 1's parts).
# The same for two agents under epsilon-greedy (fig. 17's setting), 4 seeds x 40,000 steps (about 30
# run-steps/s alone on the Intel Xeon above, about 1 h 25 min):
#     python -m mjx_curio.sweep preset=multi_agent policies=eps seeds=4 steps=40000 checkpoint_every=1000 out=runs/paper/multi_agent.spread
#     python experiments/spread_evidence.py runs/paper/multi_agent.spread
# and for two agents under UCB (fig. 18's setting), the same length and speed:
#     python -m mjx_curio.sweep preset=multi_agent policies=ucb seeds=4 steps=40000 checkpoint_every=1000 out=runs/paper/multi_agent.spread_ucb
#     python experiments/spread_evidence.py runs/paper/multi_agent.spread_ucb
# and for one UCB agent (claim 3's setting, beside the two above; 51 min alone on the Intel Xeon
# above, 46-54 run-steps/s):
#     python -m mjx_curio.sweep preset=single_agent policies=ucb seeds=4 steps=40000 checkpoint_every=1000 out=runs/paper/single_agent.spread_ucb
#     python experiments/spread_evidence.py runs/paper/single_agent.spread_ucb
# and for one Boltzmann agent (claim 10's setting, beside the one-agent epsilon-greedy and UCB ones;
# 56 min alone on the Intel Xeon above, 44-51 run-steps/s):
#     python -m mjx_curio.sweep preset=single_agent policies=boltzmann seeds=4 steps=40000 checkpoint_every=1000 out=runs/paper/single_agent.spread_boltzmann
#     python experiments/spread_evidence.py runs/paper/single_agent.spread_boltzmann
# On the last four, the curiosity from a zero memory carry, as the authors' code logs it (about
# 45 s a run beside a running sweep; docs/results/history.json, under "The paper's numbers beside
# ours"):
#     python experiments/history_evidence.py runs/paper/multi_agent.spread   # and the other three
# and what the authors' own memory logs there, trained one step from a zero state with their pairing
# of a two-agent batch and with every view beside its own step (about 1 min a two-agent run and
# 25 s a one-agent run beside a running sweep; docs/results/authors_memory.json, under the same
# heading):
#     python experiments/authors_memory_evidence.py runs/paper/multi_agent.spread   # and the other three
# The same side experiment with the posterior mean as the latent (z=mean, not the paper's
# setting: the curiosity is then the world model's error alone), 4 seeds x 40,000 steps (49 min
# on the Intel Xeon above, 46-59 run-steps/s), not run by this script either:
#     python -m mjx_curio.sweep preset=single_agent policies=eps seeds=4 steps=40000 z=mean checkpoint_every=1000 out=runs/paper/single_agent.z_mean
#     python experiments/spread_evidence.py runs/paper/single_agent.z_mean
# and for two agents under epsilon-greedy (1 h 39 min over 2 sessions on the Intel Xeon above,
# 30 run-steps/s alone):
#     python -m mjx_curio.sweep preset=multi_agent policies=eps seeds=4 steps=40000 z=mean checkpoint_every=1000 out=runs/paper/multi_agent.z_mean
#     python experiments/spread_evidence.py runs/paper/multi_agent.z_mean
# And fig. 8's setting with the authors' VAE layers (batch normalisation, leaky ReLUs, their wider
# decoder; the same seeds as single_agent.spread, beside which the page sets it under "The paper's
# numbers beside ours"), 4 seeds x 40,000 steps at 19 run-steps/s alone on a 2-core Intel Xeon
# @ 2.80GHz (lscpu family 6 model 106) on a quiet hour, 16.6 on average over 39,000 steps of
# slower ones (2 h 40 min of stepping in three sessions; 11.6-11.7 run-steps/s on the Intel Xeon
# above before their last layer became matmuls), not run by this script:
#     python -m mjx_curio.sweep preset=single_agent policies=eps seeds=4 steps=40000 vae_layers=authors checkpoint_every=1000 out=runs/paper/single_agent.authors_vae
# Beside which the page sets fig. 8's setting run again with the default layers, the same seeds
# and command as single_agent.spread on a later build that records the training batches'
# curiosity too (the page also sets the two runs of the default layers side by side), 4 seeds x
# 40,000 steps (1 h 18 min alone on the Intel Xeon @ 2.80GHz, 32-35 run-steps/s), not run by
# this script:
#     python -m mjx_curio.sweep preset=single_agent policies=eps seeds=4 steps=40000 checkpoint_every=1000 out=runs/paper/single_agent.batch_curiosity
# And fig. 17's setting with the authors' VAE layers (two epsilon-greedy agents, the seeds of
# multi_agent.spread, beside which the page sets it), 4 seeds x 40,000 steps (about 5 h 50 min of
# stepping over 3 sessions on the Intel Xeon @ 2.80GHz, 8-9.8 run-steps/s alone), not run by this
# script:
#     python -m mjx_curio.sweep preset=multi_agent policies=eps seeds=4 steps=40000 vae_layers=authors checkpoint_every=1000 out=runs/paper/multi_agent.authors_vae
# One agent under epsilon-greedy at the paper's full 80,000 steps (figs. 8-10's setting), seeds
# 0-2, 2 h 1 min alone on a 2-core AMD EPYC (CPU family 25 model 17, 33-34 run-steps/s), and
# seeds 3-5, 1 h 51 min over two sessions (the second resumed with resume=true; 38-42 run-steps/s
# alone), not run by this script; full_length_evidence.py sets them beside the committed
# single_agent runs:
#     python -m mjx_curio.sweep preset=single_agent policies=eps seeds=3 steps=80000 checkpoint_every=2000 out=runs/paper/single_agent.full_length
#     python -m mjx_curio.sweep preset=single_agent policies=eps seeds=3 first_seed=3 steps=80000 checkpoint_every=2000 out=runs/paper/single_agent.full_length.seeds-3-5
# and under UCB (figs. 23 and 24's setting: claim 3 against the main job's UCB runs), seeds 0-2,
# 1 h 50 min on the same CPU (36-38 run-steps/s alone), and seeds 3-5, 2 h 11 min over two
# sessions (the second resumed with resume=true; 34-36 run-steps/s alone); full_length_evidence.py
# reads the four as one sweep of single_agent:
#     python -m mjx_curio.sweep preset=single_agent policies=ucb seeds=3 steps=80000 checkpoint_every=2000 out=runs/paper/single_agent.full_length_ucb
#     python -m mjx_curio.sweep preset=single_agent policies=ucb seeds=3 first_seed=3 steps=80000 checkpoint_every=2000 out=runs/paper/single_agent.full_length_ucb.seeds-3-5
# and two agents under UCB (claim 3 on one machine: one agent against two on the same CPU),
# seeds 0-2, 3 h 21 min over two sessions on the same CPU (22-23 run-steps/s alone), and seeds
# 3-5, 3 h 13 min over two sessions (22-24 run-steps/s alone), each second session resumed with
# resume=true; full_length_evidence.py reads the two as one sweep and keeps it beside the main
# job as the two-agent preset on a CPU:
#     python -m mjx_curio.sweep preset=multi_agent policies=ucb seeds=3 steps=80000 checkpoint_every=2000 out=runs/paper/multi_agent.full_length_ucb
#     python -m mjx_curio.sweep preset=multi_agent policies=ucb seeds=3 first_seed=3 steps=80000 checkpoint_every=2000 out=runs/paper/multi_agent.full_length_ucb.seeds-3-5
# and two agents under epsilon-greedy (claim 3 under that policy on one machine), seeds 0-2, 3 h
# 12 min over two sessions on the same CPU (23-24 run-steps/s alone; the second resumed with
# resume=true), which full_length_evidence.py reads with the two UCB sweeps as one:
#     python -m mjx_curio.sweep preset=multi_agent policies=eps seeds=3 steps=80000 checkpoint_every=2000 out=runs/paper/multi_agent.full_length
#     python experiments/full_length_evidence.py runs/paper/single_agent.full_length runs/paper/single_agent.full_length.seeds-3-5 runs/paper/single_agent.full_length_ucb runs/paper/single_agent.full_length_ucb.seeds-3-5 runs/paper/multi_agent.full_length_ucb runs/paper/multi_agent.full_length_ucb.seeds-3-5 runs/paper/multi_agent.full_length
#
# The paper's full scale (8 seeds, 80,000 steps, every preset) is a GPU job: install the CUDA
# extra (pip install -e '.[cuda]') and run
#     SEEDS=8 STEPS=80000 bash experiments/reproduce.sh
# which is the presets' own default scale (python -m mjx_curio.sweep preset=<name>). On one NVIDIA
# H200 the two-agent preset at that scale (the main job: 24 runs x 80,000 steps) took 9 minutes;
# experiments/full_length_evidence.py puts such a sweep beside the committed 40,000-step runs.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-.venv/bin/python}
SEEDS_GIVEN=${SEEDS:-}
SEEDS=${SEEDS:-3}
MULTI_SEEDS=${MULTI_SEEDS:-${SEEDS_GIVEN:-8}}
SINGLE_SEEDS=${SINGLE_SEEDS:-${SEEDS_GIVEN:-11}}
SINGLE_WALL_SEEDS=${SINGLE_WALL_SEEDS:-${SEEDS_GIVEN:-8}}
MULTI_WALL_SEEDS=${MULTI_WALL_SEEDS:-${SEEDS_GIVEN:-8}}
TEMPERATURE_SEEDS=${TEMPERATURE_SEEDS:-${SEEDS_GIVEN:-6}}
STEPS=${STEPS:-}
MULTI_STEPS=${MULTI_STEPS:-${STEPS:-40000}}
SINGLE_STEPS=${SINGLE_STEPS:-${STEPS:-40000}}
TEMPERATURE_STEPS=${TEMPERATURE_STEPS:-${STEPS:-40000}}
WALL_STEPS=${WALL_STEPS:-${STEPS:-15000}}
# Bad settings stop here, before any sweep starts (a sweep advances in chunks of 100 steps).
for knob in SEEDS MULTI_SEEDS SINGLE_SEEDS SINGLE_WALL_SEEDS MULTI_WALL_SEEDS TEMPERATURE_SEEDS STEPS MULTI_STEPS SINGLE_STEPS TEMPERATURE_STEPS WALL_STEPS; do
    value=${!knob}
    [[ $knob == STEPS && -z $value ]] && continue  # STEPS unset: each sweep's own default
    if ! [[ $value =~ ^[1-9][0-9]*$ ]] || { [[ $knob != *SEEDS ]] && (( value % 100 )); }; then
        echo "reproduce.sh: $knob=$value: want a positive whole number$([[ $knob != *SEEDS ]] && echo ', a multiple of 100')" >&2
        exit 2
    fi
done

sweep() {  # sweep PRESET STEPS [FIRST_SEED SEEDS OUT]: start it, or continue it where it stopped (or grow it to STEPS)
    local preset=$1 steps=$2 first=${3:-0} seeds=${4:-$SEEDS} out=${5:-runs/paper/$1}
    local resume=false
    [[ -f $out/manifest.json ]] && resume=true
    "$PY" -m mjx_curio.sweep preset="$preset" seeds="$seeds" first_seed="$first" steps="$steps" \
        checkpoint_every=1000 out="$out" resume="$resume"
}

seed_parts() {  # seed_parts PRESET STEPS TOTAL PARTS [FIRST...]: SEEDS seeds in runs/paper/PRESET, the rest up to TOTAL 3 at most a sweep and a new sweep at every FIRST (where the page's experiment grew); PARTS names an array that gets every sweep's folder
    local preset=$1 steps=$2 total=$3 first=$SEEDS n grew
    local -n folders=$4
    local starts=("${@:5}")
    sweep "$preset" "$steps"
    folders=("runs/paper/$preset")
    while (( first < total )); do
        n=$(( total - first < 3 ? total - first : 3 ))
        for grew in "${starts[@]}"; do
            (( grew > first && grew < first + n )) && n=$(( grew - first ))
        done
        folders+=("runs/paper/$preset.seeds-$first-$(( first + n - 1 ))")
        sweep "$preset" "$steps" "$first" "$n" "${folders[-1]}"
        first=$(( first + n ))
    done
}

seed_parts multi_agent "$MULTI_STEPS" "$MULTI_SEEDS" multi_parts
seed_parts single_agent "$SINGLE_STEPS" "$SINGLE_SEEDS" single_parts 8  # seeds 8-10 came later
seed_parts boltzmann_temperatures "$TEMPERATURE_STEPS" "$TEMPERATURE_SEEDS" temperature_parts
sweep boltzmann_low_temperatures "$TEMPERATURE_STEPS"
seed_parts single_agent_walls_different "$WALL_STEPS" "$SINGLE_WALL_SEEDS" wall_parts
seed_parts multi_agent_walls_different "$WALL_STEPS" "$MULTI_WALL_SEEDS" multi_wall_parts

# Each needs its sweep's newest checkpoint (the one that keeps the replay buffers).
for part in "${temperature_parts[@]}"; do
    "$PY" experiments/temperature_evidence.py "$part"
done
"$PY" experiments/temperature_evidence.py runs/paper/boltzmann_low_temperatures
# Figs. 7 (one agent) and 13 (one agent, every wall different), and the two-agent sweeps' VAEs.
for part in "${single_parts[@]}" "${wall_parts[@]}" "${multi_parts[@]}" "${multi_wall_parts[@]}"; do
    "$PY" experiments/reconstruction_evidence.py "$part"  # each part keeps its own checkpoints
done
# Claim 8's ceiling: how much of each step's curiosity is noise no self-model can foresee.
for part in "${multi_parts[@]}"; do
    "$PY" experiments/self_model_evidence.py "$part"
done
"$PY" experiments/results.py snapshot runs/paper
"$PY" experiments/results.py page
"$PY" experiments/results.py check
