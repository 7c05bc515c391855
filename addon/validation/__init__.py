"""Measuring renders against a converged reference: the reference itself, looked up or
rendered and cached (reference), the renders of ``xsl-render curves`` with equal fixed costs
(contestants) and the curves job (curves_runner)."""
