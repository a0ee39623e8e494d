"""The web service: FastAPI app, routes, and the services that own time and machines."""

VERSION = "0.2.0"
