"""Test helpers: a planner node in a subprocess and its client, recorded messages, random worlds."""
