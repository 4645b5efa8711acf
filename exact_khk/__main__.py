from exact_khk.cli.main import entry_point

entry_point()
