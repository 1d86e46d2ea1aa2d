"""The contracts every process agrees on: messages, topics, the Bus, the channel, scenarios.

This package imports nothing else of the project (see DESIGN.md, import rules).
"""
