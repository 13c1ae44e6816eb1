"""Figures (matplotlib, Agg): the common style and titles, the figures of a run and those of a
sweep. Each figure is titled with the case and the settings it shows, with units on its axes.
"""
