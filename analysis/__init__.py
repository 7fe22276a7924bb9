"""Pure numerics: the beam model, responses and (later) spectra, modal identification
and the damping fit. Arrays and small dataclasses in, results out; no files, no
instrument, no printing.

Import from the submodules (``analysis.ritz``, ``analysis.exact_beam``,
``analysis.response``, ...): this package imports nothing eagerly so that the
command line starts fast.
"""
