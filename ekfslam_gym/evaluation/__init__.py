"""Evaluation: episodes, metrics, aggregation (IQM with bootstrap CIs) and reports (tables, plots, GIFs)."""
