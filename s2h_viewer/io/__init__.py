"""Reading and writing hands and motions; every writer is atomic."""
