"""What the tests share: decks written as text, FMU checks, the deck-mutation and FMI fuzz drivers,
worker programs run in their own processes, and the C hosts that load native FMUs without Python."""
