"""Strict test settings (as optimistix's): float64 on, rank promotion raises."""

import os

import jax

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_rank_promotion", "raise")

# The CLI's on-disk XLA cache stays off in tests (no writes to the home folder).
os.environ["HAIRJAX_CACHE_DIR"] = ""
