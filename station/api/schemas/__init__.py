"""Request and response schemas, one family per resource (Create / Update / Public / page)."""
