"""Autonomous jobs (sort, stack, line up, tower) and the competition scorer."""
