"""``python -m evpose ...`` runs the ``evpose`` command (for environments where its script is not on PATH)."""
from evpose.cli.main import main

main()
