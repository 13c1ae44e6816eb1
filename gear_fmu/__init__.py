"""Gear-shaft structural model: Timoshenko shafts, gear mesh element, Newmark step."""
