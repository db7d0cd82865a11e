"""AAP Workshop CMG dump mission (seed 000): a mission package of its own, because its verbs run the graph (the runtime
and the CLI's mechanism) with acds_controller's dump law and size the dump magnet with em_driver's sizing core; a node
package's code may not import the runtime, which starts its nodes, nor another package's core (docs/architecture.md "Adding a
mission")."""
