"""Helpers of the experiment engine (:mod:`skinny_mj.experiment`)."""
