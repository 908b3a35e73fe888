"""What the user runs: the command line (cli.py), the demo registry (demos.py) and their run
summaries (summaries.py), measuring helpers (analysis.py), the live window (window.py)."""
