"""What every node needs to run: main() and spinning (``spin``), callbacks that never
raise (``guard``), slow work off the executor (``builder``), /diagnostics statuses
(``diagnostics``), publishers that know their subscribers (``listened``), services that
answer later without holding up the executor (``deferred_reply``)."""
