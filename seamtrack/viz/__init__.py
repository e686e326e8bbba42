"""Views: matplotlib plots, PyVista scenes and run animations (imported only when a view is
made)."""
