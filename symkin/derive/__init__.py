"""Teaching derivations: the symbolic FK, Jacobian and Hessian of a chain, a tree or a closed-form
IK solution, written as Markdown or LaTeX (``symkin derive``)."""
