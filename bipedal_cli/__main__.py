from .cli import main

# The guard matters: evaluation workers are spawned processes, which import __main__ again.
if __name__ == "__main__":
    main()
