"""Pydantic models: the one contract for REST, websockets and the OpenAPI schema."""
