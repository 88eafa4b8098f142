"""Time-versus-error benchmark harness for Gradus (driven by bench/run)."""
