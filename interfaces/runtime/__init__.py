"""The runtime every process runs on: the Bus and its transports (in-process, Zenoh), message
encoding, admission of received messages, the channel stage, the app base class, the rate-group
executive with its lockstep client, and the command-line plumbing of a participant process.

Imports only the contracts (``interfaces.contracts``) of the project.
"""
