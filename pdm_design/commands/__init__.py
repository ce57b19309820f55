"""Commands above the layers they drive: each reads a spec, runs the api, the solver and the
yield, and shapes their answers for the command line.

yield_    `pdm-design yield` (text, JSON, figures, `check`'s min_yield) and `simulate --build`
"""
