"""The contracts every process agrees on: the messages, the topic catalogue and key
expressions, the FDI window schedule, the scenario models and the seeded random streams.

Imports nothing else of the project, not even the runtime (docs: import rules).
"""
