# Smoke run of the contact benchmark (--quick: a few solves and a 20-step trajectory); the full
# run (bench_contact) is by hand, docs/contact.md.
if(TARGET bench_contact)
  add_test(NAME bench_contact_smoke COMMAND bench_contact --quick)
endif()
