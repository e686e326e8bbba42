"""Input and output: run folders (summary, trace, frames), profile CSV files."""
