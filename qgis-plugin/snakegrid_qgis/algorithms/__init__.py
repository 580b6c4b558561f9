"""The Processing algorithms of the snakegrid provider."""
