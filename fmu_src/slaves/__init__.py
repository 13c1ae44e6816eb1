"""What an FMU runs: the pythonfmu slaves of the bearing and gear-shaft FMUs, what they
share, and the bootstrap that stages an FMU's own copy of the code. Only these modules (with
the contract, the case and the physics packages) travel inside an FMU.
"""
