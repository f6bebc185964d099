"""Evaluation, one job per module: ``rollout`` (the env factory and the one episode loop), ``episode_metrics``
(what one episode scores), ``interface`` (that an agent acts in the env's action interface), ``metrics`` (the
pure functions behind them), ``smoothing`` (the recorder and the graph smoother that judges the filter),
``export`` (TUM files for evo), ``aggregate`` (IQM with bootstrap CIs), ``report`` (tables, plots), ``gif``; and
the studies built on them (``consistency``, ``paired``, ``tradeoff``, ``replay``, ``plotting``). Nothing here
imports the agents: an agent is anything with ``reset`` and ``act``."""
