"""Command lines: argument parsing and printing only; the work is done by the packages they call."""
