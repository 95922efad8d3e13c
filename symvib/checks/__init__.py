"""Checks beside the product: independent references, peer integrators, the
stability suite and the benchmarks (their shipped data in ``symvib/checks/data``).
"""
