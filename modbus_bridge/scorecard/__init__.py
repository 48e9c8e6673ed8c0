"""`thermost scorecard`: per shipped scenario, every controller against the physical bound and the best
fixed PID (build.py), as markdown, HTML and PNG traces (report.py)."""
