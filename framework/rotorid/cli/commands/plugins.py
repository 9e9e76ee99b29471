"""``rotorid plugins``: list every registered plugin by family."""

from __future__ import annotations

NAME = "plugins"
HELP = "list the registered plugins (estimators, criteria, envelopes, data sources, signals)"


def add_arguments(parser) -> None:
    parser.add_argument("--family", help="show one family only")


def run(args) -> int:
    from rotorid.plugin.manager import FAMILIES, registry

    families = [args.family] if args.family else list(FAMILIES)
    for family in families:
        components = registry(family)
        print(f"{family}:")
        if not components:
            print("  (none)")
        for name, item in components.items():
            print(f"  {name:<16} {item.summary}  [{item.provider}]")
    return 0
