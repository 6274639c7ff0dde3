"""Comparison of the caustics-mapping render against the Mitsuba reference."""
