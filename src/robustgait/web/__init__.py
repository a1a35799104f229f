"""The web page of a person study (docs/person.md): a person ranks each batch of certified gaits, watching their
videos; the answers go into the study the moment they are given. Above :mod:`robustgait.study`, which never imports
it: the study shows a batch and waits for its answer through an asker (:class:`robustgait.web.server.PersonPage`)."""
