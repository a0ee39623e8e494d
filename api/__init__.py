"""The API contract: pydantic models for REST, websocket messages and the OpenAPI schema."""
