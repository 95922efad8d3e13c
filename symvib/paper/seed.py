"""What the paper's OCR text (the project's seed) prints for each audited equation.

:mod:`symvib.paper.audit` transcribes every printed equation into SymPy.
So that a reader (and ``tests/test_audit.py``) can check each transcription
against the paper, this module keeps, for each one, the seed's own text (an
exact substring of the seed file, ``docs/seed/`` in the checkout, the copy of
``../shared/seed/``) and the OCR-noise differences the transcription declares
(:class:`~symvib.paper.seedtex.Edit`, each with its reason).  The texts are
split into adjacent string literals only to keep the lines short; ``"\\n"``
pieces are the seed's own line breaks.

Examples
--------
>>> SEED_TEXT["eq7"][:41]
'\\\\ddot{\\\\phi} \\\\pm \\\\dot{\\\\phi}^2 t g \\\\alpha_0'
>>> sorted(OCR_EDITS)
['circle.Ek', 'circle.P_mu', 'cycloid.E', 'cycloid.F_N', 'cycloid.P_mu', 'eq2']
"""
from __future__ import annotations

from symvib.paper.seedtex import Edit

__all__ = ["SEED_FILE", "SEED_TEXT", "OCR_EDITS"]

#: The seed file's name (``docs/seed/`` of the checkout; ``../shared/seed/`` beside it).
SEED_FILE = "000_0b9d0aad8b33f6fb.txt"

#: The seed's text of each printed equation, by audit key (exact substrings of the seed file).
SEED_TEXT = {
    "eq1": (
        r"\ddot{s} + g \sin \alpha \pm \mu \left(\frac{v^2}{R_k} + g \cos \alpha "
        r"\right) = 0"
    ),
    "eq2": (
        r"\dot{x}^{2}(x) = e^{-\int \frac{2}{\sqrt{1+z'^{2}}} \left[\frac{d}{dx} "
        r"\sqrt{1+z'^{2}} \pm \mu \frac{z''}{\sqrt{1+z'^{2}}} \right] dx}." "\n"
        r"$$" "\n"
        r"\n" "\n"
        r"$$" "\n"
        r"\left[-2g \int \frac{1}{\left(1+z'^{2}\right)} \left(z' \pm \mu \right) "
        r"e^{-\int \frac{2}{\sqrt{1+z'^{2}}} \left[\frac{d}{dx} \sqrt{1+z'^{2}} "
        r"\pm \mu \frac{z''}{\sqrt{1+z'^{2}}} \right] dx + C \right]^{(2)}"
    ),
    "eq3": (
        r"\ddot{\phi} + (3tg\phi \pm \mu)\dot{\phi}^2 + \frac{g\cos^3\phi}{p}(\sin\phi "
        r"\pm \mu\cos\phi) = 0"
    ),
    "eq4": (
        r"\dot{\phi}^2 = \cos^6 \phi \left(-\frac{g}{p \cos^2 \phi} + Ce^{\mp 2\mu "
        r"\phi} \right)"
    ),
    "parabola.F_N": (
        r"F_{N,i} = mg\cos\phi + mp\cos^3\phi \left(-\frac{g}{p\cos^2\phi} + C_i "
        r"e^{\mp 2\mu\phi} \right)"
    ),
    "parabola.P_mu": (
        r"P_{\mu,i} = -\mu F_{N,i} \dot{s} = -\mu F_{N,i} \frac{p}{\cos^3 \varphi} "
        r"\dot{\varphi} =" "\n"
        r"$$" "\n"
        "" "\n"
        r"=" "\n"
        r"$$" "\n"
        r"-\mu m p \left(g \cos \varphi + p \cos^3 \varphi \left(-\frac{g}{p \cos^2 "
        r"\varphi} + C_i e^{\mp 2\mu \varphi} \right) \right) \sqrt{-\frac{g}{p "
        r"\cos^2 \varphi} + C_i e^{\mp 2\mu \varphi}}"
    ),
    "parabola.Ek": (
        r"Ek_{i}(\phi) = \frac{1}{2}mv_{i}^{2} = \frac{1}{2}m\frac{p^{2}}{\cos^{6}\phi}\dot{\phi}_{i}^{2}"
        r" = \frac{1}{2}mp^{2}\left(-\frac{g}{p\cos^{2}\phi} + C_{i}e^{\mp2\mu\phi}\right)"
    ),
    "parabola.Ep": (
        r"Ep_{i}(\phi) = \frac{1}{2}\frac{mgp}{\cos^{2}\phi}"
    ),
    "parabola.E": (
        r"E_{i}(\phi) = Ek_{i}(\phi) + Ep_{i}(\phi) =" "\n"
        r"$$" "\n"
        "" "\n"
        r"\n" "\n"
        r"$$" "\n"
        r"= \frac{1}{2}mp^{2}\left(-\frac{g}{p\cos^{2}\phi} + C_{i}e^{\mp2\mu\phi}\right) "
        r"+ \frac{1}{2}\frac{mgp}{\cos^{2}\phi}"
    ),
    "eq5": (
        r"\ddot{\phi} - \dot{\phi}^2 \left(\frac{1}{2} t g \frac{\phi}{2} \mp \mu "
        r"\right) + \left(t g \frac{\phi}{2} \pm \mu \right) \frac{g}{2R} = 0"
    ),
    "eq6": (
        r"\dot{\phi}^{2} = -\frac{\left(\frac{g}{2R}\right)}{1+4\mu^{2}} \frac{1}{\cos^{2}\frac{\phi}{2}}"
        r" \left[\left(\pm 3\mu \right) \sin \phi - \left(1 - 2\mu^{2} \right) \cos "
        r"\phi + \frac{1+4\mu^{2}}{2} + Ce^{\mp 2\mu\phi} \right]"
    ),
    "cycloid.F_N": (
        r"F_{N,i} = mg \cos \frac{\phi}{2} + m2R \cos \frac{\phi}{2}." "\n"
        r"$$" "\n"
        "" "\n"
        r"\n" "\n"
        r"$$" "\n"
        r"\left(-\frac{\left(\frac{g}{2R}\right)}{1 + 4\mu^2} \frac{1}{\cos^2 \frac{\phi}{2}} "
        r"\left[\left(\pm 3\mu\right) \sin \phi - \left(1 - 2\mu^2\right) \cos \phi "
        r"+ \frac{1 + 4\mu^2}{2} + C_i e^{\mp 2\mu \phi} \right] \right]"
    ),
    "cycloid.P_mu": (
        r"P_{\mu,i} = -\mu F_{N,i} 2R \cos \frac{\phi}{2} \phi = -\mu F_{N,i} 2R "
        r"\cos \frac{\phi}{2}." "\n"
        r"$$" "\n"
        "" "\n"
        r"\n" "\n"
        r"$$" "\n"
        r"\cdot \sqrt{-\frac{\left(\frac{g}{2R}\right)}{1 + 4\mu^2} \frac{1}{\cos^2 "
        r"\frac{\phi}{2}} \left[\left(\pm 3\mu\right) \sin \phi - \left(1 - 2\mu^2\right) "
        r"\cos \phi + \frac{1 + 4\mu^2}{2} + C_i e^{\mp 2\mu \phi} \right]}"
    ),
    "cycloid.Ek": (
        r"Ek_{i}(\phi) = 2mR^{2} \cos^{2} \frac{\phi}{2} \dot{\phi}_{i}^{2}(\phi) "
        r"= 2mR^{2} \cos^{2} \frac{\phi}{2}." "\n"
        r"$$" "\n"
        "" "\n"
        r"$$" "\n"
        r"\left(-\frac{\left(\frac{g}{2R}\right)}{1 + 4\mu^{2}} \frac{1}{\cos^{2} "
        r"\frac{\phi}{2}} \left[\left(\pm 3\mu \right) \sin \phi - \left(1 - 2\mu^{2} "
        r"\right) \cos \phi + \frac{1 + 4\mu^{2}}{2} + C_{i} e^{\mp 2\mu \phi} \right] "
        r"\right)"
    ),
    "cycloid.Ep": (
        r"Ep_{i}(\phi) = mgR \left(1 - \cos \phi \right)"
    ),
    "cycloid.E": (
        r"E_i(\phi) = Ek_i(\phi) + Ep_i(\phi) = 2mR^2 \cos^2 \frac{\phi}{2}." "\n"
        r"$$" "\n"
        "" "\n"
        r"$$" "\n"
        r"\left\{ -\frac{\left(\frac{g}{2R}\right)}{1 + 4\mu^2} \frac{1}{\cos^2 "
        r"\frac{\phi}{2}} \left[\left(\pm 3\mu\right) \sin \phi - \left(1 - 2\mu^2\right) "
        r"\cos \phi + \frac{1 + 4\mu^2}{2} + C_i e^{\mp 2\mu \phi} \right] \right\} "
        r"+" "\n"
        r"$$" "\n"
        "" "\n"
        r"$$" "\n"
        r"\left\{\n\begin{array}{l}\n-\frac{(2R)}{1+4\mu^2}\frac{1}{\cos^2\frac{\phi}{2}}\n\end{array}\n\m"
        r"iddle|\n\begin{array}{l}\n(\pm 3\mu)\sin\phi - (1-2\mu^2)\cos\phi + \frac{1+4\mu^2}{2} "
        r"+ C_i e^{\mp 2\mu\phi} \\" "\n"
        r"+\frac{1}{2}\cos\phi + C_i e^{\mp 2\mu\phi}\n\end{array}\n\right\}"
    ),
    "eq7": (
        r"\ddot{\phi} \pm \dot{\phi}^2 t g \alpha_0 + \frac{g}{R \cos \alpha_0} "
        r"\sin (\phi \pm \alpha_0) = 0"
    ),
    "eq8": (
        r"\dot{\phi}(\phi)^2 = \frac{2g}{(1 + 4tg^2\alpha_0)R\cos\alpha_0}" "\n"
        r"$$" "\n"
        "" "\n"
        r"\n" "\n"
        r"$$" "\n"
        r"\cdot [\cos(\phi \pm \alpha_0) - 2tg\alpha_0\sin(\phi \pm \alpha_0)] + "
        r"Ce^{\mp 2\phi t g \alpha_0}"
    ),
    "circle.F_N": (
        r"F_{N,i} = mg\cos\varphi + mR \cdot" "\n"
        r"$$" "\n"
        "" "\n"
        r"$$" "\n"
        r"\cdot \left(\frac{2g}{\left(1 + 4tg^2\alpha_0\right)R\cos\alpha_0} \left[\cos(\varphi "
        r"\pm \alpha_0) - 2tg\alpha_0\sin(\varphi \pm \alpha_0)\right] + C_i e^{\mp "
        r"2\varphi t g\alpha_0} \right)"
    ),
    "circle.P_mu": (
        r"P_{\mu,i} = -\mu F_{N,i} R \dot{\varphi} = -\mu F_{N,i} R" "\n"
        r"$$" "\n"
        "" "\n"
        r"$$" "\n"
        r"\cdot \left\{ -\sqrt{\frac{2g}{\left(1 + 4tg^2 \alpha_0\right) R \cos "
        r"\alpha_0} \left[\cos(\varphi \pm \alpha_0) - 2tg \alpha_0 \sin(\varphi "
        r"\pm \alpha_0)\right] + C_i e^{\mp 2\varphi g \alpha_0}} \right\}"
    ),
    "circle.Ek": (
        r"Ek_i(\varphi) = \frac{1}{2} mR^2 \dot{\varphi}_i^2(\varphi) = \frac{1}{2} "
        r"mR^2." "\n"
        r"$$" "\n"
        "" "\n"
        r"$$" "\n"
        r"\cdot \left(\frac{2g}{\left(1 + 4tg^2 \alpha_0\right)R \cos \alpha_0} "
        r"\left[\cos(\varphi \pm \alpha_0) - 2tg\alpha_0 \sin(\varphi \pm \alpha_0) "
        r"\right] + C_i e^{\mp 2\varphi g \alpha_0} \right)"
    ),
    "circle.Ep": (
        r"Ep_i(\varphi) = mgR(1 - \cos \varphi)"
    ),
    "circle.E": (
        r"E_i(\phi) = E k_i(\phi) + E p_i(\phi) = \frac{1}{2} mR^2" "\n"
        r"$$" "\n"
        "" "\n"
        r"$$" "\n"
        r"\cdot \left(\frac{2g}{\left(1 + 4tg^2 \alpha_0\right) R \cos \alpha_0} "
        r"\left[\cos \left(\phi \pm \alpha_0\right) - 2tg \alpha_0 \sin \left(\phi "
        r"\pm \alpha_0\right) \right] + C_i e^{\mp 2\phi t g \alpha_0} \right) +" "\n"
        r"$$" "\n"
        "" "\n"
        r"+" "\n"
        r"$$" "\n"
        r"m g R (1 - \cos \phi)"
    ),
}

#: Why the tg of the circle's exponent is read so (two entries declare it).
_TG = "'tg' lost its 't' (OCR): the same exponent reads 'tg alpha_0' in eq. (8) and in F_N"

#: The differences between the seed's text (after :func:`~symvib.paper.seedtex.layout`) and
#: the transcription, each declared with its reason; an equation not listed has none.
OCR_EDITS = {
    "eq2": (
        Edit(r"dx + C ]^{(2)}", r"dx} dx + C ]",
             "the OCR lost the closing brace of the inner exponent e^{-int ... dx} and the dx of the outer "
             "integral, and set the equation number (2) as an exponent"),
    ),
    "cycloid.F_N": (
        Edit(r"C_i e^{\mp 2\mu \phi} ] ]", r"C_i e^{\mp 2\mu \phi} ] )",
             "the factor opens with '(' and the OCR closes it with ']'"),
    ),
    "cycloid.P_mu": (
        Edit(r"\frac{\phi}{2} \phi =", r"\frac{\phi}{2} \dot{\phi} =",
             "the velocity's dot is lost: -mu F_N 2R cos(phi/2) phidot is -mu F_N v (v = 2R cos(phi/2) phidot), "
             "and the next side inserts sqrt(phidot^2) for it"),
    ),
    "cycloid.E": (
        Edit(r"\{ \begin{array}{l} -\frac{(2R)}{1+4\mu^2}\frac{1}{\cos^2\frac{\phi}{2}} \end{array} | "
             r"\begin{array}{l} (\pm 3\mu)\sin\phi - (1-2\mu^2)\cos\phi + \frac{1+4\mu^2}{2} + C_i e^{\mp 2\mu\phi} "
             r"\\ +\frac{1}{2}\cos\phi + C_i e^{\mp 2\mu\phi} \end{array} \}",
             r"mgR (1 - \cos \phi)",
             "the second term is garbled (an array repeating pieces of the eq. (6) bracket); it is read from "
             "the printed definition E_i = Ek_i + Ep_i, with Ep_i = mgR(1 - cos phi) printed just above"),
    ),
    "circle.P_mu": (Edit(r"\varphi g \alpha_0", r"\varphi \tan \alpha_0", _TG),),
    "circle.Ek": (Edit(r"\varphi g \alpha_0", r"\varphi \tan \alpha_0", _TG),),
}
