"""Multiple importance sampling heuristics (Veach and Guibas 1995).

The weight of a sample drawn by strategy a, whose density is ``pdf_a``, when
strategy b (density ``pdf_b`` at the same point) is combined with it. The
degenerate cases are defined: 0 where ``pdf_a`` is 0 (0/0 included), 1
where ``pdf_a`` is infinite and ``pdf_b`` finite, 0.5 where both are
infinite; never NaN.
"""

from ._core.mis import balance_heuristic, power_heuristic

__all__ = ["balance_heuristic", "power_heuristic"]
