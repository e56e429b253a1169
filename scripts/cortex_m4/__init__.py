"""The parts of scripts/cycles.py: the traced run (`trace`), the Cortex-M4 cost model
(`timing`) and the cases it measures (`cases`)."""
