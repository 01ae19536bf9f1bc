"""Bayesian calibration of a campaign's parameters on flight data (`uqflight calibrate`).

surrogate.py  the only module here that uses other uqflight modules: PCE surrogate of a results
              file with its leave-one-out error, the campaign, the simulator for predictive runs
likelihood.py flight data (CSV), noise model and the vectorised log posterior in ξ (and log σ)
sampler.py    emcee ensemble, seeded, and the convergence rule
outputs.py    posterior.h5, strict summary.json, calibrated.yaml, plots
run.py        the pipeline; command.py the typer command (`register(app)`)
"""
