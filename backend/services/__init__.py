"""The service's parts: machines, real-time loop, telemetry, storage, authorization."""
