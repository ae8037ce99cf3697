"""Design tools: sound sampling, cooperative (framer) gains, and the method-specific designs."""
